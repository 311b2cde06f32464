#pragma once
// The geometry a backend builds from: triangle meshes and spheres, each shape with its own geometry id.
//
// Geometry ids number the scene's shapes in file order (meshes and spheres interleaved); a mesh's
// primitive ids are triangle indices into `indices`, a sphere's only primitive id is 0.
// A backend may keep pointers into this structure (Embree shares the vertex and index buffers), so the
// SceneGeometry must outlive every backend built from it.
//
// Invariants established by the loaders (core/scene/geometry_cleanup.h):
//  - every vertex referenced by `indices` is finite and every index is in range;
//  - no triangle is degenerate (zero area or a repeated vertex): such triangles are dropped and counted;
//  - positions.capacity() > positions.size(): Embree reads a vertex buffer with 16-byte loads, so the last
//    vertex must be followed by 4 readable bytes (see rtcSetSharedGeometryBuffer).

#include "core/geometry/bounds.h"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace twinray {

struct TriangleMesh {
  std::uint32_t geom_id = 0;
  std::vector<glm::vec3> positions;
  std::vector<glm::uvec3> indices;  // counter-clockwise seen from the front

  std::size_t triangle_count() const { return indices.size(); }
  Bounds3 bounds() const {
    Bounds3 b;
    for (const glm::uvec3& tri : indices)
      for (int k = 0; k < 3; ++k) b.extend(positions[tri[k]]);
    return b;
  }
};

struct Sphere {
  std::uint32_t geom_id = 0;
  glm::vec3 center{0.0f};
  float radius = 1.0f;

  Bounds3 bounds() const { return {center - glm::vec3(radius), center + glm::vec3(radius)}; }
};

struct SceneGeometry {
  std::vector<TriangleMesh> meshes;
  std::vector<Sphere> spheres;

  std::size_t triangle_count() const {
    std::size_t n = 0;
    for (const TriangleMesh& m : meshes) n += m.triangle_count();
    return n;
  }
  std::size_t sphere_count() const { return spheres.size(); }
  std::size_t primitive_count() const { return triangle_count() + sphere_count(); }
  bool has_triangles() const { return triangle_count() > 0; }
  bool has_spheres() const { return !spheres.empty(); }
  // One past the largest geometry id in use.
  std::uint32_t geom_id_end() const {
    std::uint32_t end = 0;
    for (const TriangleMesh& m : meshes) end = end > m.geom_id + 1 ? end : m.geom_id + 1;
    for (const Sphere& s : spheres) end = end > s.geom_id + 1 ? end : s.geom_id + 1;
    return end;
  }
  Bounds3 bounds() const {
    Bounds3 b;
    for (const TriangleMesh& m : meshes) b.extend(m.bounds());
    for (const Sphere& s : spheres) b.extend(s.bounds());
    return b;
  }
};

}  // namespace twinray
