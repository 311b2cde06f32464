#pragma once
// The SAH cost model a plugin reports its tree's cost in (twinray_build_stats::sah_cost, docs/plugin-abi.md),
// so the tree-quality check can compare it with the reference builder's tree:
//
//   C = sum over interior nodes n of  A(n) / A(root) * 1
//     + sum over leaves l of          A(l) / A(root) * N(l) * 1
//
// A(.) is the surface area of the node's bounding box, N(l) the number of primitives in leaf l (triangles
// and spheres alike), the costs of a traversal step and of a primitive test both 1. It is the expected
// number of node visits plus primitive tests of a ray that crosses the root box (MacDonald and Booth 1990),
// with the textbook's unit costs, so any binary BVH can report it from its node boxes and leaf sizes.
// A tree of one leaf over N primitives costs N.

#include "core/geometry/bounds.h"
#include "core/geometry/scene_geometry.h"

#include <cstddef>
#include <span>

namespace twinray::grade {

struct TreeNodeCost {
  Bounds3 box;
  std::size_t primitives = 0;  // 0: an interior node
};

// C for a tree given as its nodes (the root first). 0 for an empty tree.
double sah_cost_unit_model(std::span<const TreeNodeCost> nodes);

// C of the tree twinray's own builder (backends/bvh, binned SAH) makes for `geometry` when tuned to the same
// unit costs: the figure a plugin's reported cost is compared with.
double reference_sah_cost(const SceneGeometry& geometry);

}  // namespace twinray::grade
