#pragma once
// Binned SAH BVH construction over axis-aligned boxes (Wald 2007, "On fast construction of SAH-based
// bounding volume hierarchies"). The builder knows nothing about triangles or spheres: it sees one box per
// primitive and returns the node array and the order in which the primitives must be stored.

#include "backends/bvh/bvh_build_options.h"
#include "backends/bvh/bvh_builder_memory.h"
#include "backends/bvh/bvh_node.h"
#include "backends/simd/isa.h"
#include "core/geometry/bounds.h"

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace twinray {

struct BvhTree {
  // Depth-first; nodes[0] is the root. On build memory (bvh_builder_memory.h): the builder writes its
  // gapped tree into this very array and compacts it in place, and the capacity stays the gapped
  // tree's (2 n - 1 nodes for n primitives).
  std::vector<BvhNode, BuildAllocator<BvhNode>> nodes;
  // Primitive ids in leaf order: a leaf covers prim_order[first_prim, first_prim + prim_count).
  // (The backend later rebases leaf offsets into per-kind arrays.)
  std::vector<std::uint32_t> prim_order;
  std::size_t leaves = 0;
  std::size_t max_depth = 0;
};

// Builds a tree over `bounds` (primitive id = index). Primitives with id >= second_kind_begin are of a
// second kind (spheres after triangles) and never share a leaf with the first kind; a leaf whose
// primitives are of the second kind is marked with BvhNode::kSphereLeafBit. An empty input gives an empty
// tree (no nodes). Deterministic: the same input and options give the same tree, parallel or not, on
// every instruction set: `isa` only picks the kernel that bins large ranges (AVX2 or SSE2).
BvhTree build_bvh(std::span<const Bounds3> bounds, std::uint32_t second_kind_begin, const BvhBuildOptions& options,
                  Isa isa = selected_isa());

// SAH cost of a finished tree: traversal_cost per interior node and intersection_cost per primitive of a
// leaf, each weighted by the node's surface area relative to the root's. Not part of build_bvh(): the
// bvh backend reports it, bvh8 reports its wide tree's cost instead and would pay a serial pass for nothing.
double sah_cost(std::span<const BvhNode> nodes, const BvhBuildOptions& options);

}  // namespace twinray
