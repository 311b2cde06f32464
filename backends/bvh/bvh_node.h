#pragma once
// The BVH node: 32 bytes, two per 64-byte cache line, in one flat array in depth-first order.
//
// Depth-first order means an interior node's first child is always the next node (index + 1), so only the
// second child's index is stored. The field that holds it is the first primitive index in a leaf, and
// `count` tells the two apart (0 for interior nodes). Leaves never mix primitive kinds (the builder splits
// mixed leaves by kind), so one bit of `count` says which array the leaf's primitives live in, and a
// mixed scene pays one branch per leaf, not per primitive.

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>

namespace twinray {

// Deepest node the builder creates (the root has depth 0). The traversal stack holds one entry per level,
// so a stack of this many entries cannot overflow. The builder switches to object-median splits, which
// halve the primitive count, well before the cap (see bvh_builder.cpp).
inline constexpr std::size_t kBvhMaxDepth = 128;

// Aligned so that (lo, offset) and (hi, count) are each one aligned 16-byte load (see ray_box.h).
struct alignas(32) BvhNode {
  static constexpr std::uint32_t kSphereLeafBit = 0x80000000u;

  glm::vec3 lo;
  std::uint32_t offset;  // interior: index of the second child; leaf: first primitive in its kind's array
  glm::vec3 hi;
  std::uint32_t count;   // interior: 0; leaf: number of primitives, | kSphereLeafBit for a sphere leaf

  bool is_leaf() const { return count != 0; }
  bool is_sphere_leaf() const { return (count & kSphereLeafBit) != 0; }
  std::uint32_t prim_count() const { return count & ~kSphereLeafBit; }
  std::uint32_t second_child() const { return offset; }
  std::uint32_t first_prim() const { return offset; }
};
static_assert(sizeof(BvhNode) == 32, "two nodes per cache line");

}  // namespace twinray
