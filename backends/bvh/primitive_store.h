#pragma once
// The BVH's private copy of the geometry, in leaf order.
//
// Primitives are reordered once, at build time, so that the primitives of a leaf are adjacent in memory and
// a leaf test streams through one contiguous block: triangles as their three vertices (no index
// indirection), spheres as center and radius. Ids, which only the winning hit needs, live in parallel
// arrays so they do not dilute the cache lines the tests read.
//
// Vertices are copied bit for bit from the SceneGeometry: the watertight test relies on neighbouring
// triangles seeing identical coordinates for shared vertices, and the bvh must produce exactly the t, u, v
// of the brute-force oracle.

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace twinray {

struct StoredTriangle {
  glm::vec3 p0, p1, p2;
};
static_assert(sizeof(StoredTriangle) == 36);

struct StoredSphere {
  glm::vec3 center;
  float radius;
};
static_assert(sizeof(StoredSphere) == 16);

// Where a stored primitive came from.
struct PrimitiveKey {
  std::uint32_t geom_id;
  std::uint32_t prim_id;
};

struct PrimitiveStore {
  std::vector<StoredTriangle> triangles;
  std::vector<PrimitiveKey> triangle_keys;  // parallel to `triangles`
  std::vector<StoredSphere> spheres;
  std::vector<PrimitiveKey> sphere_keys;    // parallel to `spheres`

  std::size_t memory_bytes() const {
    return triangles.capacity() * sizeof(StoredTriangle) + triangle_keys.capacity() * sizeof(PrimitiveKey) +
           spheres.capacity() * sizeof(StoredSphere) + sphere_keys.capacity() * sizeof(PrimitiveKey);
  }
};

}  // namespace twinray
