#pragma once
// Filling a PrimitiveStore in leaf order from a scene: shared by the bvh and the wide backends, whose
// builders both return primitive ids (triangles first, in mesh order, then spheres) in leaf order.

#include "backends/bvh/primitive_store.h"
#include "core/geometry/bounds.h"
#include "core/geometry/scene_geometry.h"

#include <cstdint>
#include <span>
#include <vector>

namespace twinray {

// One box per primitive, indexed by primitive id: triangles first (in mesh order), then spheres.
std::vector<Bounds3> primitive_bounds(const SceneGeometry& geometry);

class PrimitiveGatherer {
 public:
  // `geometry` must outlive the gatherer; `store` is cleared.
  PrimitiveGatherer(const SceneGeometry& geometry, PrimitiveStore& store);

  // Appends a leaf of triangles (primitive ids < triangle count) as a run of whole blocks; the last block
  // is padded with copies of the last triangle, masked off by the traversal. Returns its first slot.
  std::uint32_t append_triangles(std::span<const std::uint32_t> ids);
  // Appends a leaf of spheres (primitive ids >= triangle count). Returns its first index in `spheres`.
  std::uint32_t append_spheres(std::span<const std::uint32_t> ids);
  // Releases spare capacity once every leaf is in.
  void finish();

 private:
  struct TriangleSource {
    const TriangleMesh* mesh;
    std::uint32_t index;
  };
  const SceneGeometry& geometry_;
  PrimitiveStore& store_;
  std::vector<TriangleSource> triangle_source_;  // by primitive id
};

}  // namespace twinray
