#pragma once
// The child references of a wide node (wide_node.h), WideRef, and what a triangle leaf reference means to the
// traversal: the blocks of the PrimitiveStore it tests and the lanes of each that hold its triangles.
//
// A reference names the leaf's first slot (block * 4 + lane) and its triangle count; leaves share blocks
// (LeafPacking::kSharedBlocks, primitive_gather.h), so a leaf of one to three triangles may start at any lane
// where it fits, and never touches more blocks than ceil(count / 4). The leaf's lanes, over its consecutive
// blocks, are one run of `count` bits starting at bit `lane`: bits 4k..4k+3 are block k's lanes. The run is at
// most 3 + 16 bits long (WideRef::kMaxLeafCount), so it fits a 32-bit mask.
//
// A triangle reference holds the block and the lane apart (the block in bits 0..23, the lane in bits 24..25),
// so that the traversal reads the first block with one mask and the lanes from one table indexed by the
// reference's top byte (leaf bit, sphere bit, count - 1, lane): two instructions and a load of a 1 KiB table
// instead of the run's shifts (about 7 instructions fewer per leaf, docs/bvh-backend.md, thirteenth round).
//
// Walking a leaf:
//     const WideTriangleLeaf leaf = wide_triangle_leaf(ref);
//     std::uint32_t block = leaf.block;
//     for (std::uint32_t lanes = leaf.lanes; lanes != 0; lanes >>= kTriangleBlockLanes, ++block)
//       test block `block` on lanes (lanes & kWideBlockLaneMask); lane i is slot block * 4 + i.

#include "backends/bvh/primitive_store.h"

#include <array>
#include <cstdint>

namespace twinray {

struct WideRef {
  static constexpr std::uint32_t kLeafBit = 0x80000000u;
  static constexpr std::uint32_t kSphereBit = 0x40000000u;
  // count - 1 in bits 26..29: leaves of at most 16 (the collapse forms leaves of at most 8 by default, and
  // the binary tree's are of at most 3), which leaves 26 bits for a first slot: 2^26 slots (the triangles
  // plus the padding lanes of partly filled blocks, a few percent) or 2^26 spheres; WideBackend::build
  // refuses a larger scene with an error. A triangle leaf's 26 bits are the block (bits 0..23) and the lane
  // (bits 24..25); a sphere leaf's are the first sphere.
  static constexpr int kCountShift = 26;
  static constexpr std::uint32_t kMaxLeafCount = 16;
  static constexpr std::uint32_t kFirstMask = (1u << kCountShift) - 1;
  static constexpr int kLaneShift = 24;
  static constexpr std::uint32_t kBlockMask = (1u << kLaneShift) - 1;

  static constexpr bool is_leaf(std::uint32_t ref) { return (ref & kLeafBit) != 0; }
  static constexpr bool is_sphere_leaf(std::uint32_t ref) { return (ref & kSphereBit) != 0; }
  static constexpr std::uint32_t count(std::uint32_t ref) { return ((ref >> kCountShift) & (kMaxLeafCount - 1)) + 1; }
  // A sphere leaf's first sphere.
  static constexpr std::uint32_t first_sphere(std::uint32_t ref) { return ref & kFirstMask; }
  // A triangle leaf's first slot.
  static constexpr std::uint32_t first_slot(std::uint32_t ref) {
    return (ref & kBlockMask) * kTriangleBlockLanes + ((ref >> kLaneShift) & (kTriangleBlockLanes - 1));
  }
  // For triangles the first slot, for spheres the first sphere.
  static constexpr std::uint32_t first(std::uint32_t ref) {
    return is_sphere_leaf(ref) ? first_sphere(ref) : first_slot(ref);
  }
  // `first`: for triangles the first slot (any lane of a block; below 2^26), for spheres the first sphere.
  static constexpr std::uint32_t leaf(std::uint32_t first, std::uint32_t count, bool spheres) {
    const std::uint32_t low =
        spheres ? first : (first / kTriangleBlockLanes) | ((first % kTriangleBlockLanes) << kLaneShift);
    return kLeafBit | (spheres ? kSphereBit : 0u) | ((count - 1) << kCountShift) | low;
  }
};
static_assert(WideRef::kMaxLeafCount << WideRef::kCountShift == WideRef::kSphereBit, "count bits below the sphere bit");
static_assert(kTriangleBlockLanes == 4 && (WideRef::kFirstMask >> 2) == WideRef::kBlockMask,
              "a 26-bit slot is a 24-bit block and a 2-bit lane");

inline constexpr std::uint32_t kWideBlockLaneMask = (1u << kTriangleBlockLanes) - 1;

struct WideTriangleLeaf {
  std::uint32_t block;  // the first block
  std::uint32_t lanes;  // bit 4k + i: lane i of block `block + k` holds one of the leaf's triangles
};

static_assert(kTriangleBlockLanes - 1 + WideRef::kMaxLeafCount <= 32, "a leaf's lanes fit one 32-bit mask");

// The lanes of a triangle leaf, by its reference's top byte (leaf bit, sphere bit, count - 1, lane): the run of
// count ones shifted to the lane. 0 for the bytes of inner and sphere references, which never index it.
inline constexpr std::array<std::uint32_t, 256> kWideLeafLanes = [] {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t top = 0; top < 256; ++top) {
    const std::uint32_t ref = top << 24;
    if (!WideRef::is_leaf(ref) || WideRef::is_sphere_leaf(ref)) continue;
    const std::uint32_t run = (2u << (WideRef::count(ref) - 1)) - 1;  // count ones (count is 1..16)
    table[top] = run << ((ref >> WideRef::kLaneShift) & (kTriangleBlockLanes - 1));
  }
  return table;
}();

// For a triangle leaf reference (WideRef::is_leaf and not is_sphere_leaf).
[[gnu::always_inline]] constexpr WideTriangleLeaf wide_triangle_leaf(std::uint32_t ref) {
  return {ref & WideRef::kBlockMask, kWideLeafLanes[ref >> 24]};
}

}  // namespace twinray
