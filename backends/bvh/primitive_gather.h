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

// How triangle leaves are laid out in the store's blocks of four.
enum class LeafPacking {
  // Every leaf starts a block (the bvh backend's layout: its leaves are addressed by block).
  kBlockAligned,
  // A leaf may start at any lane where it touches no more blocks than ceil(count / 4), the fewest it can:
  // a leaf of 1 to 3 triangles then shares its block with the leaves before it while lanes remain, so
  // small leaves do not each leave a partly empty block behind (the bvh8 backend, whose leaf references
  // name a first lane; wide_leaf_ref.h). Block tests per leaf are the same as with kBlockAligned.
  kSharedBlocks,
};

// Replaces `store` with the leaves' primitives, leaf after leaf in the order given: a triangle leaf as a
// run of lanes placed by `packing`, a sphere leaf as a run of spheres. The lanes no leaf holds (the end of
// a block that the next leaf did not fit in) repeat the triangle before them and are keyed kPadding; the
// traversal masks them off. Returns, per leaf, where it starts: its first triangle slot (with
// kBlockAligned the first lane of a block), or its first index in `spheres`.
//
// Two passes: the offsets (a sequential pass over the leaves, so every array is allocated once at its
// final size), then the copies, leaves in parallel. The layout does not depend on the thread count.
std::vector<std::uint32_t> gather_leaves(const SceneGeometry& geometry, std::span<const std::uint32_t> prim_order,
                                         std::span<const LeafToGather> leaves, PrimitiveStore& store,
                                         LeafPacking packing = LeafPacking::kBlockAligned);

}  // namespace twinray
