#pragma once
// The wide BVH backend, name() == "bvh8": the binned SAH binary tree of the bvh backend (bvh_builder.h),
// collapsed by cost into 8-wide nodes (wide_collapse.h) over the same leaf-ordered primitive store, and
// traversed by SIMD kernels chosen at run time for SSE2, AVX2 or AVX-512 (wide_kernels.h).

#include "backends/bvh/bvh_build_options.h"
#include "backends/bvh/primitive_store.h"
#include "backends/simd/isa.h"
#include "backends/wide/wide_any_order.h"
#include "backends/wide/wide_collapse.h"
#include "backends/wide/wide_kernels.h"
#include "backends/wide/wide_node.h"
#include "core/backend/backend.h"

#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace twinray {

struct WideBuildOptions {
  BvhBuildOptions binary = default_binary();
  WideCollapseOptions collapse;
  // The any-hit order (wide_kernels.h); by default chosen per tree from its leaf boxes (wide_any_order.h).
  std::optional<AnyHitOrder> any_hit_order;

  // The binary tree the collapse starts from. Its leaves are the smallest the wide tree can have, so it
  // is built with cheaper interior steps than the bvh backend's (1:1 instead of 3:1) and leaves of at most
  // three triangles, and the collapse merges them where a bigger leaf pays. Leaves of up to 8 left the
  // collapse no choice inside them (a leaf of big triangles spanning a room stayed one leaf); up to 4 kept
  // a ground plane's triangles in leaves with small ones; 1 or 2 give nearly the same wide trees as 3
  // and cost 10% more build (docs/bvh-backend.md, "Cost model").
  static BvhBuildOptions default_binary() {
    BvhBuildOptions o;
    o.traversal_cost = 1.0f;
    o.max_leaf_size = 3;
    return o;
  }
};

class WideBackend final : public Backend {
 public:
  // Throws std::invalid_argument on bad options. `isa` picks the traversal kernels (tests run every path);
  // by default the widest this CPU supports, lowered by $TWINRAY_ISA (backends/simd/isa.h).
  explicit WideBackend(const WideBuildOptions& options = {}, std::optional<Isa> isa = std::nullopt);

  std::string_view name() const override { return "bvh8"; }
  BackendTraits traits() const override { return {.counts_traversal = true, .honours_ties = true, .watertight = true}; }

  void build(const SceneGeometry& geometry) override;
  BuildStats build_stats() const override { return stats_; }

  bool intersect(const Ray& ray, Hit& hit, QueryStats* stats = nullptr) const override;
  // The same traversal without the winner's u, v and ng (about a fifth of a closest-hit query's work on the
  // Cornell box): they stay as a miss has them.
  bool intersect_ids(const Ray& ray, Hit& hit, QueryStats* stats = nullptr) const override;
  bool occluded(const Ray& ray, QueryStats* stats = nullptr) const override;
  // Batches are traced in the Morton order of their ray origins (ray_order.h), like the bvh backend's.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, QueryStats* stats = nullptr) const override;
  void occluded(std::span<const Ray> rays, std::span<std::uint8_t> occluded, QueryStats* stats = nullptr) const override;

  // Read-only access to the tree, for tests and tools.
  Isa isa() const { return isa_; }
  // The any-hit order the last build took, with the statistic it was chosen by (zero when the order was given).
  const AnyHitOrderChoice& any_hit_order() const { return any_hit_order_; }
  std::span<const WideNode> nodes() const { return nodes_; }
  const PrimitiveStore& primitives() const { return prims_; }

 private:
  WideBuildOptions options_;
  Isa isa_;
  WideKernels kernels_;  // null until build() saw at least one primitive
  std::vector<WideNode> nodes_;
  PrimitiveStore prims_;
  Bounds3 bounds_;       // of the whole scene, for the Morton order of batches
  BuildStats stats_;
  AnyHitOrderChoice any_hit_order_;
};

std::unique_ptr<Backend> make_wide_backend(const WideBuildOptions& options = {}, std::optional<Isa> isa = std::nullopt);

}  // namespace twinray
