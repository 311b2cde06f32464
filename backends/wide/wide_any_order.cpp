#include "backends/wide/wide_any_order.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace twinray {
namespace {

// Surface area of a box from its float corners, in double: the differences and products of floats up to 2^128
// stay finite (below 2^257), so no box overflows to infinity.
double surface_area(double dx, double dy, double dz) { return 2.0 * (dx * dy + dy * dz + dz * dx); }

bool filled(const WideNode& node, int s) { return node.lo[0][s] <= node.hi[0][s]; }

}  // namespace

double wide_leaf_depth_complexity(std::span<const WideNode> nodes) {
  if (nodes.empty()) return 0.0;
  // The root box: the union of the root node's boxes.
  double lo[3], hi[3];
  std::fill(lo, lo + 3, std::numeric_limits<double>::infinity());
  std::fill(hi, hi + 3, -std::numeric_limits<double>::infinity());
  for (int s = 0; s < kWideWidth; ++s)
    if (filled(nodes[0], s))
      for (int a = 0; a < 3; ++a) lo[a] = std::min<double>(lo[a], nodes[0].lo[a][s]), hi[a] = std::max<double>(hi[a], nodes[0].hi[a][s]);
  const double root = surface_area(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  // No filled slot (-inf - inf), or a root box flat in two axes (a line: area 0): no meaningful ratio.
  if (!(root > 0.0) || !std::isfinite(root)) return 0.0;
  // Each node's leaf areas summed in float, branch-free over its eight slots (an empty slot has hi - lo = -inf,
  // so dx >= 0 is false, as is the leaf bit for an inner child): about a quarter of the instructions of a
  // double per slot. Float's rounding (a relative 2^-21 over eight terms) does not matter to a threshold;
  // a box past about 2^63 across overflows the float products, and the double sum below is then redone.
  double leaves = 0.0;
  for (const WideNode& node : nodes) {
    float sum = 0.0f;
    for (int s = 0; s < kWideWidth; ++s) {
      const float dx = node.hi[0][s] - node.lo[0][s], dy = node.hi[1][s] - node.lo[1][s], dz = node.hi[2][s] - node.lo[2][s];
      const float area = dx * dy + dy * dz + dz * dx;
      sum += WideRef::is_leaf(node.child[s]) && dx >= 0.0f ? area : 0.0f;
    }
    leaves += sum;
  }
  if (!std::isfinite(leaves)) {
    leaves = 0.0;
    for (const WideNode& node : nodes)
      for (int s = 0; s < kWideWidth; ++s)
        if (filled(node, s) && WideRef::is_leaf(node.child[s]))
          leaves += 0.5 * surface_area(static_cast<double>(node.hi[0][s]) - node.lo[0][s],
                                       static_cast<double>(node.hi[1][s]) - node.lo[1][s],
                                       static_cast<double>(node.hi[2][s]) - node.lo[2][s]);
  }
  return 2.0 * leaves / root;
}

AnyHitOrderChoice choose_any_hit_order(std::span<const WideNode> nodes) {
  AnyHitOrderChoice choice;
  choice.leaf_depth = wide_leaf_depth_complexity(nodes);
  if (choice.leaf_depth >= kWideNearestMinLeafDepth) choice.chosen = AnyHitOrder::kNearest;
  return choice;
}

}  // namespace twinray
