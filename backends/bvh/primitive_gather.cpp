#include "backends/bvh/primitive_gather.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace twinray {

std::vector<Bounds3> primitive_bounds(const SceneGeometry& geometry) {
  std::vector<Bounds3> bounds(geometry.primitive_count());
  std::size_t at = 0;
  for (const TriangleMesh& mesh : geometry.meshes) {
    // Large meshes in parallel blocks: a linear pass that would otherwise run alone before the build.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.indices.size(), 1u << 14),
                      [&, at](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i < r.end(); ++i) {
                          const glm::uvec3& tri = mesh.indices[i];
                          Bounds3 b = Bounds3::of_point(mesh.positions[tri.x]);
                          b.extend(mesh.positions[tri.y]);
                          b.extend(mesh.positions[tri.z]);
                          bounds[at + i] = b;
                        }
                      });
    at += mesh.indices.size();
  }
  for (const Sphere& s : geometry.spheres) bounds[at++] = s.bounds();
  return bounds;
}

PrimitiveGatherer::PrimitiveGatherer(const SceneGeometry& geometry, PrimitiveStore& store)
    : geometry_(geometry), store_(store) {
  store_ = PrimitiveStore{};
  triangle_source_.reserve(geometry.triangle_count());
  for (const TriangleMesh& mesh : geometry.meshes)
    for (std::size_t i = 0; i < mesh.indices.size(); ++i)
      triangle_source_.push_back({&mesh, static_cast<std::uint32_t>(i)});
  // Blocks: at least one per four triangles, more where leaves leave lanes empty.
  store_.triangle_blocks.reserve(geometry.triangle_count() / 2 + 1);
  store_.triangle_keys.reserve(2 * geometry.triangle_count() + 4);
  store_.spheres.reserve(geometry.sphere_count());
  store_.sphere_keys.reserve(geometry.sphere_count());
}

std::uint32_t PrimitiveGatherer::append_triangles(std::span<const std::uint32_t> ids) {
  const auto first = static_cast<std::uint32_t>(store_.triangle_keys.size());
  const auto count = static_cast<std::uint32_t>(ids.size());
  const std::uint32_t slots = (count + kTriangleBlockLanes - 1) / kTriangleBlockLanes * kTriangleBlockLanes;
  for (std::uint32_t j = 0; j < slots; ++j) {
    const std::uint32_t lane = j % kTriangleBlockLanes;
    if (lane == 0) store_.triangle_blocks.emplace_back();
    const TriangleSource& src = triangle_source_[ids[std::min(j, count - 1)]];
    const glm::uvec3& tri = src.mesh->indices[src.index];
    const std::vector<glm::vec3>& p = src.mesh->positions;
    store_.triangle_blocks.back().set(lane, p[tri.x], p[tri.y], p[tri.z]);
    store_.triangle_keys.push_back(j < count ? PrimitiveKey{src.mesh->geom_id, src.index}
                                             : PrimitiveKey{PrimitiveKey::kPadding, PrimitiveKey::kPadding});
  }
  return first;
}

std::uint32_t PrimitiveGatherer::append_spheres(std::span<const std::uint32_t> ids) {
  const auto first = static_cast<std::uint32_t>(store_.spheres.size());
  const std::size_t n_triangles = triangle_source_.size();
  for (const std::uint32_t id : ids) {
    const Sphere& s = geometry_.spheres[id - n_triangles];
    store_.spheres.push_back({s.center, s.radius});
    store_.sphere_keys.push_back({s.geom_id, 0});
  }
  return first;
}

void PrimitiveGatherer::finish() {
  store_.triangle_blocks.shrink_to_fit();
  store_.triangle_keys.shrink_to_fit();
}

}  // namespace twinray
