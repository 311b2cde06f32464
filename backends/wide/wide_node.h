#pragma once
// The 8-wide BVH node: eight child boxes in structure-of-arrays form, tested together by one SIMD slab
// test (wide_box.h), and eight child references.
//
// Layout: lo[axis][slot] and hi[axis][slot], each row one 32-byte aligned vector of eight floats, then the
// children: 224 bytes, seven 32-byte units (Embree's 8-wide node is 256). Boxes are plain floats, not
// quantised: the tree then needs no dequantisation on the hot path, and its memory still stays below
// Embree's (docs/bvh-backend.md has the figures).
//
// Unused slots hold the empty box (lo = +inf, hi = -inf), which the slab test never hits (every slab
// distance of the near plane is +inf and of the far plane -inf, for any finite origin and any
// direction), so traversal needs no count of children. Filled slots come first.
//
// A child reference is either another node (top bit clear: its byte offset in the node array, index * 224, so
// that the traversal reads a node's rows at a per-ray row pointer plus the reference, with no multiplication on
// the path from one node to the next; the collapse writes indices and WideBackend::build converts them) or a
// leaf (top bit set) naming a run of primitives in the PrimitiveStore: for triangles the first slot (block * 4 + lane: leaves share
// blocks, LeafPacking::kSharedBlocks in primitive_gather.h) and the number of triangles, for spheres the
// first sphere and their number. Leaves never mix kinds. The encoding (WideRef) and what a triangle leaf
// means to the traversal are in wide_leaf_ref.h.

#include "backends/wide/wide_leaf_ref.h"

#include <cstddef>
#include <cstdint>
#include <limits>

namespace twinray {

inline constexpr int kWideWidth = 8;

struct alignas(32) WideNode {
  float lo[3][kWideWidth];
  float hi[3][kWideWidth];
  std::uint32_t child[kWideWidth];

  // Offset in floats of row lo[axis] (hi[axis] is 3 * kWideWidth further).
  static constexpr std::size_t lo_row(int axis) { return static_cast<std::size_t>(axis) * kWideWidth; }
  static constexpr std::size_t hi_row(int axis) { return lo_row(axis) + 3 * kWideWidth; }
};
static_assert(sizeof(WideNode) == 224, "seven 32-byte units");

// An inner child reference: the node's byte offset (see above), below the leaf bit for every node of a tree of at
// most kWideMaxNodes nodes (WideBackend::build refuses a larger tree: 2^31 bytes of nodes, about 9.6 million).
inline constexpr std::uint32_t kWideMaxNodes = static_cast<std::uint32_t>((WideRef::kLeafBit - 1) / sizeof(WideNode) + 1);
static_assert(std::uint64_t{kWideMaxNodes - 1} * sizeof(WideNode) < WideRef::kLeafBit, "the last node's offset is not a leaf");
static_assert(std::uint64_t{kWideMaxNodes} * sizeof(WideNode) >= WideRef::kLeafBit, "no node more would fit");
constexpr std::uint32_t wide_inner_ref(std::uint32_t index) {
  return index * static_cast<std::uint32_t>(sizeof(WideNode));
}
constexpr std::uint32_t wide_node_index(std::uint32_t ref) { return ref / static_cast<std::uint32_t>(sizeof(WideNode)); }

// The traversal stack holds at most (width - 1) entries per level below the root.
inline constexpr std::size_t kWideMaxDepth = 128;
inline constexpr std::size_t kWideStackSize = kWideMaxDepth * (kWideWidth - 1) + 1;

}  // namespace twinray
