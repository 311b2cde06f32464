#pragma once
// The hand-written BVH backend: binned SAH tree (bvh_builder.h) over a leaf-ordered private copy of the
// geometry (primitive_store.h), traversed by bvh_traversal.inl (bvh_kernels.h). name() == "bvh".

#include "backends/bvh/bvh_build_options.h"
#include "backends/bvh/bvh_kernels.h"
#include "backends/bvh/bvh_node.h"
#include "backends/bvh/primitive_store.h"
#include "core/backend/backend.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace twinray {

// One node entered by a traced query (see BvhBackend::intersect_traced).
struct BvhVisit {
  std::uint32_t node;  // index into nodes()
  float tmax;          // end of the interval still searched when the node was entered
};

class BvhBackend final : public Backend {
 public:
  // Throws std::invalid_argument on bad options. `isa` picks the traversal kernels (tests run every path);
  // by default the widest this CPU supports, lowered by $TWINRAY_ISA (backends/simd/isa.h).
  explicit BvhBackend(const BvhBuildOptions& options = {}, std::optional<Isa> isa = std::nullopt);

  std::string_view name() const override { return "bvh"; }
  BackendTraits traits() const override { return {.counts_traversal = true, .honours_ties = true, .watertight = true}; }

  void build(const SceneGeometry& geometry) override;
  BuildStats build_stats() const override { return stats_; }

  bool intersect(const Ray& ray, Hit& hit, QueryStats* stats = nullptr) const override;
  bool occluded(const Ray& ray, QueryStats* stats = nullptr) const override;
  // A batch is traced in the Morton order of its ray origins (ray_order.h): same answers as a loop of
  // single-ray calls, fewer cache misses on incoherent rays.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, QueryStats* stats = nullptr) const override;
  void occluded(std::span<const Ray> rays, std::span<std::uint8_t> occluded, QueryStats* stats = nullptr) const override;

  // The same queries (same code, same answers) that also record every node entered, in order: the visit
  // order `twinray trace` prints. Not for hot paths: they allocate.
  bool intersect_traced(const Ray& ray, Hit& hit, std::vector<BvhVisit>& visits, QueryStats* stats = nullptr) const;
  bool occluded_traced(const Ray& ray, std::vector<BvhVisit>& visits, QueryStats* stats = nullptr) const;

  // Read-only access to the tree, for tests and tools.
  const BvhBuildOptions& options() const { return options_; }
  Isa isa() const { return isa_; }
  std::span<const BvhNode> nodes() const { return nodes_; }
  const PrimitiveStore& primitives() const { return prims_; }

 private:
  BvhBuildOptions options_;
  Isa isa_;
  BvhKernels kernels_;  // null until build() saw at least one primitive
  std::vector<BvhNode> nodes_;
  PrimitiveStore prims_;
  BuildStats stats_;
};

std::unique_ptr<twinray::Backend> make_bvh_backend(const BvhBuildOptions& options = {}, std::optional<Isa> isa = std::nullopt);

}  // namespace twinray
