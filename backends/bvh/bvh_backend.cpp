#include "backends/bvh/bvh_backend.h"

#include "backends/bvh/bvh_builder.h"
#include "backends/bvh/primitive_gather.h"
#include "backends/bvh/ray_order.h"

#include <algorithm>
#include <chrono>

namespace twinray {

BvhBackend::BvhBackend(const BvhBuildOptions& options, std::optional<Isa> isa)
    : options_(options), isa_(isa ? *isa : selected_isa()) {
  validate(options_);
}

void BvhBackend::build(const SceneGeometry& geometry) {
  const auto start = std::chrono::steady_clock::now();

  const std::size_t n_triangles = geometry.triangle_count();
  BvhTree tree = build_bvh(primitive_bounds(geometry), static_cast<std::uint32_t>(n_triangles), options_, isa_);
  const double tree_cost = sah_cost(tree.nodes, options_);

  // Leaves appear in depth-first order with increasing ranges of prim_order; each is copied to its kind's
  // array in that order and its offset rebased to that array (primitive_gather.h).
  std::vector<LeafToGather> leaves;
  leaves.reserve(tree.leaves);
  for (const BvhNode& node : tree.nodes)
    if (node.is_leaf()) leaves.push_back({node.first_prim(), node.prim_count(), node.is_sphere_leaf()});
  const std::vector<std::uint32_t> offsets = gather_leaves(geometry, tree.prim_order, leaves, prims_);
  std::size_t next_leaf = 0;
  for (BvhNode& node : tree.nodes)
    if (node.is_leaf()) node.offset = offsets[next_leaf++];
  nodes_.assign(tree.nodes.begin(), tree.nodes.end());  // exact size: tree.nodes keeps the gapped tree's capacity

  const bool has_triangles = n_triangles > 0, has_spheres = geometry.has_spheres();
  kernels_ = has_triangles || has_spheres ? bvh_kernels(isa_, has_triangles, has_spheres) : BvhKernels{};

  stats_ = BuildStats{};
  stats_.triangles = n_triangles;
  stats_.spheres = geometry.sphere_count();
  stats_.built_triangles = has_triangles;
  stats_.built_spheres = has_spheres;
  stats_.nodes = nodes_.size();
  stats_.leaves = tree.leaves;
  stats_.max_depth = tree.max_depth;
  stats_.sah_cost = tree_cost;
  stats_.memory_bytes = nodes_.capacity() * sizeof(BvhNode) + prims_.memory_bytes();
  stats_.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

bool BvhBackend::intersect(const Ray& ray, Hit& hit, QueryStats* stats) const {
  if (stats) ++stats->queries;
  if (!is_valid_ray(ray)) {  // checked up front: an invalid ray must not sweep the tree
    hit = Hit{};
    return false;
  }
  if (kernels_.intersect == nullptr) {
    hit = Hit{};
    return false;
  }
  return kernels_.intersect(BvhView{nodes_, &prims_}, ray, hit, stats);
}

bool BvhBackend::occluded(const Ray& ray, QueryStats* stats) const {
  if (stats) ++stats->queries;
  if (!is_valid_ray(ray)) return false;
  return kernels_.occluded != nullptr && kernels_.occluded(BvhView{nodes_, &prims_}, ray, stats);
}

void BvhBackend::intersect(std::span<const Ray> rays, std::span<Hit> hits, QueryStats* stats) const {
  if (nodes_.empty()) return Backend::intersect(rays, hits, stats);
  // Traced in the Morton order of their origins (ray_order.h); each answer lands in its ray's slot.
  const Bounds3 bounds{nodes_[0].lo, nodes_[0].hi};
  for (const std::uint32_t i : morton_ray_order(rays, bounds)) intersect(rays[i], hits[i], stats);
}

void BvhBackend::occluded(std::span<const Ray> rays, std::span<std::uint8_t> occluded, QueryStats* stats) const {
  if (nodes_.empty()) return Backend::occluded(rays, occluded, stats);
  const Bounds3 bounds{nodes_[0].lo, nodes_[0].hi};
  for (const std::uint32_t i : morton_ray_order(rays, bounds)) occluded[i] = this->occluded(rays[i], stats) ? 1 : 0;
}

std::unique_ptr<Backend> make_bvh_backend(const BvhBuildOptions& options, std::optional<Isa> isa) {
  return std::make_unique<BvhBackend>(options, isa);
}

}  // namespace twinray
