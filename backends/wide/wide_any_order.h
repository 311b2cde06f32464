#pragma once
// Chooses a built tree's any-hit order (AnyHitOrder, wide_kernels.h) from the tree itself, without tracing:
// the nearest-first order is taken when the leaves' depth complexity is high.
//
// Why per tree: neither order wins everywhere (docs/bvh-backend.md, "Tenth round, scale series"). In volumes of
// small primitives (soups, the hairball) the child the ray enters first is the cheaper way to an occluder
// (soup-1M shadow rays: 206 node boxes per ray stored-first, 123 nearest-first); in a building the larger child,
// a wall or a floor, is (Sponza interior camera rays: 36 against 54). The answers are the same whichever order is
// chosen; only the work differs.
//
// The statistic: the leaves' depth complexity, the sum of the leaf boxes' surface areas over the root box's.
// For a random line through the root box (uniform in the Cauchy-Crofton sense) the chance of crossing a convex
// box inside it is the ratio of their surface areas, so the sum is the expected number of leaf boxes such a line
// crosses. Where it is high, a segment that starts on a surface meets many leaves, each likely to hold an
// occluder near the start, and visiting the nearest child first finds one after few nodes; where it is low (a
// surface mesh: about 1 with the ground plane, whose box is most of the root's), the larger child stored first
// is as likely a way to an occluder. One pass over the nodes, O(nodes): no probe, so no cost that grows with a
// query's length (the tenth round's 256-segment probe took 15% of the hairball-256k build).

#include "backends/wide/wide_kernels.h"
#include "backends/wide/wide_node.h"

#include <span>

namespace twinray {

struct AnyHitOrderChoice {
  double leaf_depth = 0.0;  // the leaves' depth complexity (above); 0 for an empty tree or a flat root box
  AnyHitOrder chosen = AnyHitOrder::kStored;
};

// The depth complexity from which nearest first is taken. Measured on the issue-12 trees (docs/bvh-backend.md,
// "Eleventh round, any-hit"): every mesh and view 0.8 to 2.3, except the Sponza interior (no ground plane) at
// 7.6, whose own rays lose 14 to 48% of their node visits with nearest first; spheres 2.4 to 2.6, terrains 1.3
// to 1.4; soups 12.6 to 30.4, the hairball 11.1 to 163. The threshold lies between the interior and the lowest
// soup or hairball, about 1.2 times from either.
inline constexpr double kWideNearestMinLeafDepth = 9.5;

// The leaves' depth complexity of a tree (nodes[0] the root; empty slots have lo > hi), summed in double in
// node order: the same value on every instruction set and run.
double wide_leaf_depth_complexity(std::span<const WideNode> nodes);

AnyHitOrderChoice choose_any_hit_order(std::span<const WideNode> nodes);

}  // namespace twinray
