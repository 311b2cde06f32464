#include "backends/wide/wide_any_order.h"

#include <emmintrin.h>

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
  // Each node's leaf areas summed in float, four slots at a time (SSE2, which every x86-64 CPU has; this unit is
  // compiled for the baseline, so the sum is the same on every machine): an empty slot has hi - lo = -inf, so
  // dx >= 0 is false, and an inner child has the leaf bit clear. About 45 instructions per node instead of about
  // 200 for a scalar loop in double. Float's rounding (a relative 2^-21 over eight terms) does not matter to a
  // threshold; a box past about 2^63 across overflows the float products, and the sum is then redone in double.
  static_assert(kWideWidth == 8, "two groups of four slots");
  double leaves = 0.0;
  for (const WideNode& node : nodes) {
    __m128 sum = _mm_setzero_ps();
    for (int h = 0; h < kWideWidth; h += 4) {
      const __m128 dx = _mm_sub_ps(_mm_load_ps(&node.hi[0][h]), _mm_load_ps(&node.lo[0][h]));
      const __m128 dy = _mm_sub_ps(_mm_load_ps(&node.hi[1][h]), _mm_load_ps(&node.lo[1][h]));
      const __m128 dz = _mm_sub_ps(_mm_load_ps(&node.hi[2][h]), _mm_load_ps(&node.lo[2][h]));
      const __m128 area = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dy), _mm_mul_ps(dy, dz)), _mm_mul_ps(dz, dx));
      const __m128i child = _mm_load_si128(reinterpret_cast<const __m128i*>(&node.child[h]));
      const __m128 leaf = _mm_castsi128_ps(_mm_srai_epi32(child, 31));  // all ones where the leaf bit is set
      static_assert(WideRef::kLeafBit == 0x80000000u, "the leaf bit is the sign bit");
      sum = _mm_add_ps(sum, _mm_and_ps(_mm_and_ps(leaf, _mm_cmpge_ps(dx, _mm_setzero_ps())), area));
    }
    alignas(16) float lanes[4];
    _mm_store_ps(lanes, sum);
    leaves += static_cast<double>((lanes[0] + lanes[1]) + (lanes[2] + lanes[3]));
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
