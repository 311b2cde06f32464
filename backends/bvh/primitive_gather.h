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

// A leaf of a finished tree: prim_order[first, first + count), all triangles or all spheres.
struct LeafToGather {
  std::uint32_t first;
  std::uint32_t count;
  bool spheres;
};

// Replaces `store` with the leaves' primitives, leaf after leaf in the order given: a triangle leaf as a
// run of whole blocks (its last block padded with copies of its last triangle, masked off by the
// traversal), a sphere leaf as a run of spheres. Returns, per leaf, where it starts: the triangle slot of
// its first block, or its first index in `spheres`.
//
// Two passes: the offsets (a prefix sum over the leaves, so every array is allocated once at its final
// size), then the copies, leaves in parallel. The layout does not depend on the thread count.
std::vector<std::uint32_t> gather_leaves(const SceneGeometry& geometry, std::span<const std::uint32_t> prim_order,
                                         std::span<const LeafToGather> leaves, PrimitiveStore& store);

}  // namespace twinray
