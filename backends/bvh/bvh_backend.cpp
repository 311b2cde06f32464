#include "backends/bvh/bvh_backend.h"

#include "backends/bvh/bvh_builder.h"
#include "backends/bvh/bvh_traversal.h"
#include "backends/bvh/ray_order.h"

#include <algorithm>
#include <chrono>

namespace twinray {

BvhBackend::BvhBackend(const BvhBuildOptions& options) : options_(options) { validate(options_); }

void BvhBackend::build(const SceneGeometry& geometry) {
  const auto start = std::chrono::steady_clock::now();

  // One box per primitive: triangles first (in mesh order), then spheres; the id is the index.
  const std::size_t n_triangles = geometry.triangle_count();
  std::vector<Bounds3> bounds;
  bounds.reserve(geometry.primitive_count());
  for (const TriangleMesh& mesh : geometry.meshes) {
    for (const glm::uvec3& tri : mesh.indices) {
      Bounds3 b = Bounds3::of_point(mesh.positions[tri.x]);
      b.extend(mesh.positions[tri.y]);
      b.extend(mesh.positions[tri.z]);
      bounds.push_back(b);
    }
  }
  for (const Sphere& s : geometry.spheres) bounds.push_back(s.bounds());

  BvhTree tree = build_bvh(bounds, static_cast<std::uint32_t>(n_triangles), options_);

  // Where primitive id k comes from, to gather the store in leaf order.
  struct TriangleSource {
    const TriangleMesh* mesh;
    std::uint32_t index;
  };
  std::vector<TriangleSource> triangle_source;
  triangle_source.reserve(n_triangles);
  for (const TriangleMesh& mesh : geometry.meshes)
    for (std::size_t i = 0; i < mesh.indices.size(); ++i)
      triangle_source.push_back({&mesh, static_cast<std::uint32_t>(i)});

  prims_ = PrimitiveStore{};
  prims_.spheres.reserve(geometry.sphere_count());
  prims_.sphere_keys.reserve(geometry.sphere_count());
  // Leaves appear in depth-first order with increasing ranges of prim_order; each is appended to its
  // kind's array and its offset rebased to that array. A triangle leaf starts a new block of four and pads
  // its last block with copies of its last triangle (masked off in traversal, see primitive_store.h).
  for (BvhNode& node : tree.nodes) {
    if (!node.is_leaf()) continue;
    const std::uint32_t first = node.first_prim(), count = node.prim_count();
    if (node.is_sphere_leaf()) {
      node.offset = static_cast<std::uint32_t>(prims_.spheres.size());
      for (std::uint32_t k = first; k < first + count; ++k) {
        const Sphere& s = geometry.spheres[tree.prim_order[k] - n_triangles];
        prims_.spheres.push_back({s.center, s.radius});
        prims_.sphere_keys.push_back({s.geom_id, 0});
      }
    } else {
      node.offset = static_cast<std::uint32_t>(prims_.triangle_keys.size());
      const std::uint32_t slots = (count + kTriangleBlockLanes - 1) / kTriangleBlockLanes * kTriangleBlockLanes;
      for (std::uint32_t j = 0; j < slots; ++j) {
        const std::uint32_t lane = j % kTriangleBlockLanes;
        if (lane == 0) prims_.triangle_blocks.emplace_back();
        const TriangleSource& src = triangle_source[tree.prim_order[first + std::min(j, count - 1)]];
        const glm::uvec3& tri = src.mesh->indices[src.index];
        const std::vector<glm::vec3>& p = src.mesh->positions;
        prims_.triangle_blocks.back().set(lane, p[tri.x], p[tri.y], p[tri.z]);
        prims_.triangle_keys.push_back(j < count ? PrimitiveKey{src.mesh->geom_id, src.index}
                                                 : PrimitiveKey{PrimitiveKey::kPadding, PrimitiveKey::kPadding});
      }
    }
  }
  prims_.triangle_blocks.shrink_to_fit();
  prims_.triangle_keys.shrink_to_fit();
  nodes_ = std::move(tree.nodes);

  const bool has_triangles = n_triangles > 0, has_spheres = geometry.has_spheres();
  kinds_ = has_triangles ? (has_spheres ? Kinds::Mixed : Kinds::Triangles) : (has_spheres ? Kinds::Spheres : Kinds::None);

  stats_ = BuildStats{};
  stats_.triangles = n_triangles;
  stats_.spheres = geometry.sphere_count();
  stats_.built_triangles = has_triangles;
  stats_.built_spheres = has_spheres;
  stats_.nodes = nodes_.size();
  stats_.leaves = tree.leaves;
  stats_.max_depth = tree.max_depth;
  stats_.sah_cost = tree.sah_cost;
  stats_.memory_bytes = nodes_.capacity() * sizeof(BvhNode) + prims_.memory_bytes();
  stats_.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

bool BvhBackend::intersect(const Ray& ray, Hit& hit, QueryStats* stats) const {
  if (stats) ++stats->queries;
  if (!is_valid_ray(ray)) {  // checked up front: an invalid ray must not sweep the tree
    hit = Hit{};
    return false;
  }
  const BvhView view{nodes_, &prims_};
  switch (kinds_) {
    case Kinds::Triangles: return bvh_intersect<true, false>(view, ray, hit, stats);
    case Kinds::Spheres: return bvh_intersect<false, true>(view, ray, hit, stats);
    case Kinds::Mixed: return bvh_intersect<true, true>(view, ray, hit, stats);
    case Kinds::None: break;
  }
  hit = Hit{};
  return false;
}

bool BvhBackend::occluded(const Ray& ray, QueryStats* stats) const {
  if (stats) ++stats->queries;
  if (!is_valid_ray(ray)) return false;
  const BvhView view{nodes_, &prims_};
  switch (kinds_) {
    case Kinds::Triangles: return bvh_occluded<true, false>(view, ray, stats);
    case Kinds::Spheres: return bvh_occluded<false, true>(view, ray, stats);
    case Kinds::Mixed: return bvh_occluded<true, true>(view, ray, stats);
    case Kinds::None: break;
  }
  return false;
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

std::unique_ptr<Backend> make_bvh_backend(const BvhBuildOptions& options) { return std::make_unique<BvhBackend>(options); }

}  // namespace twinray
