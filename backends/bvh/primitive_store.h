#pragma once
// The BVH's private copy of the geometry, in leaf order.
//
// Primitives are reordered once, at build time, so that the primitives of a leaf are adjacent in memory and
// a leaf test streams through one contiguous block. Triangles are stored four to a TriangleBlock, in
// structure-of-arrays form, so that one SIMD watertight test covers four triangles (triangle_block.h).
// In the bvh backend each leaf starts a new block; in bvh8 leaves share blocks, a leaf never touching more
// blocks than it must (LeafPacking, primitive_gather.h). Lanes no leaf holds repeat the triangle before
// them and are masked off. Spheres are stored as center and radius. Ids, which only the winning hit needs, live in
// parallel arrays so they do not dilute the cache lines the tests read.
//
// Vertices are copied bit for bit from the SceneGeometry: the watertight test relies on neighbouring
// triangles seeing identical coordinates for shared vertices, and the bvh must produce exactly the t, u, v
// of the brute-force oracle.

#include "backends/bvh/bvh_builder_memory.h"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace twinray {

inline constexpr std::uint32_t kTriangleBlockLanes = 4;

// Four triangles: v[vertex][axis][lane]. 144 bytes, 16-byte aligned so each (vertex, axis) row is one
// aligned SSE load.
struct alignas(16) TriangleBlock {
  float v[3][3][kTriangleBlockLanes];

  glm::vec3 vertex(std::uint32_t vert, std::uint32_t lane) const {
    return {v[vert][0][lane], v[vert][1][lane], v[vert][2][lane]};
  }
  void set(std::uint32_t lane, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2) {
    const glm::vec3* p[3] = {&p0, &p1, &p2};
    for (std::uint32_t vert = 0; vert < 3; ++vert)
      for (std::uint32_t axis = 0; axis < 3; ++axis) v[vert][axis][lane] = (*p[vert])[static_cast<int>(axis)];
  }
};
static_assert(sizeof(TriangleBlock) == 144);

struct StoredSphere {
  glm::vec3 center;
  float radius;
};
static_assert(sizeof(StoredSphere) == 16);

// Where a stored primitive came from.
struct PrimitiveKey {
  static constexpr std::uint32_t kPadding = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t geom_id;
  std::uint32_t prim_id;
  bool is_padding() const { return geom_id == kPadding; }
};

struct PrimitiveStore {
  // On build memory (bvh_builder_memory.h): large arrays on huge pages, and resize() leaves the elements
  // uninitialised, since the gather writes every one of them (value-initialising them was a zero-fill of
  // the whole store on one thread before the parallel gather wrote it again).
  template <class T>
  using Array = std::vector<T, BuildAllocator<T>>;

  // Triangle slot s is lane s % 4 of block s / 4. A triangle leaf starts at a slot: the first lane of a
  // block in bvh (BvhNode::first_prim), any lane in bvh8 (WideRef, wide_leaf_ref.h).
  Array<TriangleBlock> triangle_blocks;
  Array<PrimitiveKey> triangle_keys;  // per slot; padding lanes hold kPadding
  Array<StoredSphere> spheres;
  Array<PrimitiveKey> sphere_keys;    // parallel to `spheres`

  const TriangleBlock& block_of(std::uint32_t slot) const { return triangle_blocks[slot / kTriangleBlockLanes]; }
  glm::vec3 triangle_vertex(std::uint32_t slot, std::uint32_t vert) const {
    return block_of(slot).vertex(vert, slot % kTriangleBlockLanes);
  }

  std::size_t memory_bytes() const {
    return triangle_blocks.capacity() * sizeof(TriangleBlock) + triangle_keys.capacity() * sizeof(PrimitiveKey) +
           spheres.capacity() * sizeof(StoredSphere) + sphere_keys.capacity() * sizeof(PrimitiveKey);
  }
};

}  // namespace twinray
