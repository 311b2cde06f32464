#include "backends/wide/wide_backend.h"

#include "backends/bvh/bvh_builder.h"
#include "backends/bvh/primitive_gather.h"
#include "backends/bvh/ray_order.h"
#include "backends/wide/wide_any_order.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>

namespace twinray {

WideBackend::WideBackend(const WideBuildOptions& options, std::optional<Isa> isa)
    : options_(options), isa_(isa ? *isa : selected_isa()) {
  validate(options_.binary);
  validate(options_.collapse);
  if (options_.binary.max_leaf_size > static_cast<int>(WideRef::kMaxLeafCount))
    throw std::invalid_argument("bvh8: the binary tree's max_leaf_size must be at most 16");
}

void WideBackend::build(const SceneGeometry& geometry) {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n_triangles = geometry.triangle_count();
  // Leaf references hold a 26-bit first slot (wide_leaf_ref.h). Padding lanes make the slots a few percent
  // more than the triangles, so the exact check comes after the gather; this one refuses a scene that
  // cannot fit before minutes of building it.
  if (std::max(n_triangles, geometry.sphere_count()) > std::size_t{WideRef::kFirstMask} + 1)
    throw std::length_error("bvh8: too many primitives for 26-bit leaf references (at most 2^26 triangles or spheres)");
  const BvhTree binary = build_bvh(primitive_bounds(geometry), static_cast<std::uint32_t>(n_triangles), options_.binary, isa_);
  WideTree tree = collapse_to_wide(binary, options_.collapse);
  // Inner references become byte offsets below the leaf bit (wide_node.h).
  if (tree.nodes.size() > kWideMaxNodes)
    throw std::length_error("bvh8: too many nodes for 31-bit node references (at most 2^31 bytes of nodes)");

  // The collapse numbers the leaves in node order, so siblings' primitives are neighbours in the store too.
  std::vector<LeafToGather> leaves(tree.leaves.size());
  std::transform(tree.leaves.begin(), tree.leaves.end(), leaves.begin(),
                 [](const WideLeafRange& leaf) { return LeafToGather{leaf.first_prim, leaf.count, leaf.spheres}; });
  // Leaves share blocks: a reference names a first slot, not a first block (wide_leaf_ref.h); inner references
  // name a node by its byte offset (wide_node.h).
  // Into a new store, taken over only once every reference fits: a build that throws leaves the previous
  // tree, store and kernels together.
  PrimitiveStore prims;
  const std::vector<std::uint32_t> offsets =
      gather_leaves(geometry, binary.prim_order, leaves, prims, LeafPacking::kSharedBlocks);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tree.nodes.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t n = r.begin(); n < r.end(); ++n)
      for (std::uint32_t& child : tree.nodes[n].child) {
        if (!WideRef::is_leaf(child)) {  // a node's index (0 in an empty slot, never read)
          child = wide_inner_ref(child);
          continue;
        }
        const std::uint32_t index = child & ~WideRef::kLeafBit;
        const LeafToGather& leaf = leaves[index];
        if (offsets[index] > WideRef::kFirstMask)
          throw std::length_error("bvh8: too many primitives for 26-bit leaf references (at most 2^26 slots)");
        child = WideRef::leaf(offsets[index], leaf.count, leaf.spheres);
      }
  });
  prims_ = std::move(prims);
  nodes_ = std::move(tree.nodes);
  nodes_.shrink_to_fit();
  bounds_ = binary.nodes.empty() ? Bounds3{} : Bounds3{binary.nodes[0].lo, binary.nodes[0].hi};

  const bool has_triangles = n_triangles > 0, has_spheres = geometry.has_spheres();
  kernels_ = WideKernels{};
  any_hit_order_ = AnyHitOrderChoice{};
  if (has_triangles || has_spheres) {
    // From the tree's leaf boxes (wide_any_order.h), unless given.
    if (options_.any_hit_order) any_hit_order_.chosen = *options_.any_hit_order;
    else any_hit_order_ = choose_any_hit_order(nodes_);
    kernels_ = wide_kernels(isa_, has_triangles, has_spheres, any_hit_order_.chosen);
  }

  stats_ = BuildStats{};
  stats_.triangles = n_triangles;
  stats_.spheres = geometry.sphere_count();
  stats_.built_triangles = has_triangles;
  stats_.built_spheres = has_spheres;
  stats_.nodes = nodes_.size();
  stats_.leaves = tree.leaves.size();
  stats_.max_depth = tree.max_depth;
  stats_.sah_cost = tree.sah_cost;
  stats_.memory_bytes = nodes_.capacity() * sizeof(WideNode) + prims_.memory_bytes();
  stats_.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The kernels check the ray themselves (wide_kernels.h).
bool WideBackend::intersect(const Ray& ray, Hit& hit, QueryStats* stats) const {
  if (stats) ++stats->queries;
  if (kernels_.intersect == nullptr) {
    hit = Hit{};
    return false;
  }
  return kernels_.intersect(WideView{nodes_.data(), &prims_}, ray, hit, stats);
}

bool WideBackend::intersect_ids(const Ray& ray, Hit& hit, QueryStats* stats) const {
  if (stats) ++stats->queries;
  if (kernels_.intersect_ids == nullptr) {
    hit = Hit{};
    return false;
  }
  return kernels_.intersect_ids(WideView{nodes_.data(), &prims_}, ray, hit, stats);
}

bool WideBackend::occluded(const Ray& ray, QueryStats* stats) const {
  if (stats) ++stats->queries;
  if (kernels_.occluded == nullptr) return false;
  return kernels_.occluded(WideView{nodes_.data(), &prims_}, ray, stats);
}

void WideBackend::intersect(std::span<const Ray> rays, std::span<Hit> hits, QueryStats* stats) const {
  if (nodes_.empty()) return Backend::intersect(rays, hits, stats);
  for (const std::uint32_t i : morton_ray_order(rays, bounds_)) intersect(rays[i], hits[i], stats);
}

void WideBackend::occluded(std::span<const Ray> rays, std::span<std::uint8_t> occluded, QueryStats* stats) const {
  if (nodes_.empty()) return Backend::occluded(rays, occluded, stats);
  for (const std::uint32_t i : morton_ray_order(rays, bounds_)) occluded[i] = this->occluded(rays[i], stats) ? 1 : 0;
}

std::unique_ptr<Backend> make_wide_backend(const WideBuildOptions& options, std::optional<Isa> isa) {
  return std::make_unique<WideBackend>(options, isa);
}

}  // namespace twinray
