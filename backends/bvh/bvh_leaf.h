#pragma once
// `bvh`'s own leaf tests: the block tests of triangle_block.h (same answers, bit for bit) with the
// candidate's t and the per-block hit decision on shorter dependency chains (eleventh round,
// docs/bvh-backend.md). `bvh`'s primary rays cost time, not instructions, against c1d6bc7: each candidate's
// t feeds tmax, every later box test and stack pop depends on tmax, and a mispredicted branch on them waits
// for the whole chain. Kept apart from triangle_block.h, whose edge test `bvh8` shares.

#include "backends/bvh/triangle_block.h"

#include <xmmintrin.h>

#include <cstdint>

namespace twinray::bvh_leaf {

using refine_detail::Crossing;
using triangle_block_detail::EdgeLanes;

// triangle_block_detail::edge_test with `exact_zero` from three compares instead of the product u v w: the
// same lanes (an edge function exactly 0, or a NaN, goes to decide_in_double; see there), but the per-block
// branch on the result waits for one compare, not two products and a compare. A lane whose product u v w
// underflowed went to decide_in_double before and is a candidate here; its edge functions are non-zero and
// not NaN, so their signs are exact (triangle_watertight.h) and the scalar test decided it alike.
[[gnu::always_inline]] inline EdgeLanes edge_test(const TriangleRay& ray, const TriangleBlock& block, unsigned lanes) {
  const triangle_block_detail::EdgeFunctions e = triangle_block_detail::edge_functions(ray, block);
  const __m128 u = e.u, v = e.v, w = e.w;

  // Undecided: a zero (== 0) or a NaN (unordered) edge function. Independent compares, one level of ORs.
  const __m128 zero = _mm_setzero_ps();
  const __m128 undecided =
      _mm_or_ps(_mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(u, zero), _mm_cmpeq_ps(v, zero)),
                          _mm_or_ps(_mm_cmpeq_ps(w, zero), _mm_cmpunord_ps(u, v))),
                _mm_cmpunord_ps(w, w));
  const unsigned exact_zero = static_cast<unsigned>(_mm_movemask_ps(undecided)) & lanes;
  // Among the others (none 0 or NaN) the signs are mixed exactly when the sign bits differ.
  const unsigned mixed_signs =
      static_cast<unsigned>(_mm_movemask_ps(_mm_or_ps(_mm_xor_ps(u, v), _mm_xor_ps(u, w))));
  return {lanes & ~exact_zero & ~mixed_signs, exact_zero};
}

// refine_detail::refine_t_kept_v<false> (the same answers) with the certified t taken from the quotient x
// itself rather than from the interval's ends: t_ends's lower end is x - slack rounded, and slack (a second
// division and three operations) is only needed to *certify* the rounding. When certified, lo == hi, and
// lo = fl32(fl64(x - slack)) <= fl32(x) <= fl32(fl64(x + slack)) = hi (slack >= 0; x is a double, so the
// double roundings of x -+ slack lie on either side of it, and rounding to float is monotonic), so
// fl32(x) == lo: the same float, one conversion after the division. The certificate becomes a branch
// (nearly always taken), so the t that tmax and the later box tests wait for no longer waits for the slack.
// The interval test below needs no repeat for a certified t: hi >= tmin and lo <= tmax were just tested.
template <typename Exact>
[[gnu::always_inline]] inline bool refine_t(const refine_detail::RefineRay& ray, const glm::vec3& q0,
                                            const glm::vec3& q1, const glm::vec3& q2, float tmin, float tmax,
                                            float& t_out, Crossing& c, const Exact& exact) {
  using namespace refine_detail;
  float t = 0.0f;
  if (crossing_sums(ray, load(q0), load(q1), load(q2), c)) {
    const Ends ends = t_ends(c);
    if (ends.hi < tmin || ends.lo > tmax) return false;
    if (ends.certified()) {
      t_out = static_cast<float>(c.num / c.den);  // == ends.lo, see above
      return true;
    }
    t = ends.lo;
  }
  float u, v;
  if (!exact(t, u, v)) return false;
  if (!(t >= tmin && t <= tmax)) return false;
  t_out = t;
  return true;
}

// intersect_triangle_block_closest (triangle_block.h) on the two functions above.
template <typename OnHit>
[[gnu::always_inline]] inline void block_closest(const TriangleRay& ray, const TriangleBlock& block, unsigned lanes,
                                                 float tmin, float tmax, const OnHit& on_hit) {
  using namespace triangle_block_detail;
  const EdgeLanes edges = bvh_leaf::edge_test(ray, block, lanes);
  if ((edges.candidates | edges.exact_zero) == 0) return;
  for (unsigned m = edges.candidates; m != 0; m &= m - 1) {
    const unsigned lane = static_cast<unsigned>(__builtin_ctz(m));
    Crossing crossing;
    float t;
    if (!bvh_leaf::refine_t(ray.refine, block.vertex(0, lane), block.vertex(1, lane), block.vertex(2, lane), tmin,
                            tmax, t, crossing, [&ray, &block, lane](float& te, float& ue, float& ve) {
                              return exact_crossing_of_lane(ray, block, lane, te, ue, ve);
                            }))
      continue;
    tmax = on_hit(lane, t, &crossing);
  }
  if (edges.exact_zero != 0) {
    BlockHits found;
    for (unsigned m = decide_in_double<Report::kT>(ray, block, edges.exact_zero, tmin, tmax, found); m != 0;
         m &= m - 1) {
      const unsigned lane = static_cast<unsigned>(__builtin_ctz(m));
      tmax = on_hit(lane, found.t[lane], static_cast<const Crossing*>(nullptr));
    }
  }
}

// intersect_triangle_block_any<true> (triangle_block.h) on the edge test above.
[[gnu::always_inline]] inline bool block_any(const TriangleRay& ray, const TriangleBlock& block, unsigned lanes,
                                             float tmin, float tmax) {
  using namespace triangle_block_detail;
  const EdgeLanes edges = bvh_leaf::edge_test(ray, block, lanes);
  if ((edges.candidates | edges.exact_zero) == 0) return false;
  for (unsigned m = edges.candidates; m != 0; m &= m - 1) {
    const unsigned lane = static_cast<unsigned>(__builtin_ctz(m));
    const auto exact = [&ray, &block, lane](float& te, float& ue, float& ve) {
      return exact_crossing_of_lane(ray, block, lane, te, ue, ve);
    };
    if (refine_detail::refine_in_interval</*kDivisionFreeFirst=*/true>(
            ray.refine, block.vertex(0, lane), block.vertex(1, lane), block.vertex(2, lane), tmin, tmax, exact))
      return true;
  }
  if (edges.exact_zero == 0) return false;
  BlockHits unused;
  return decide_in_double<Report::kAny>(ray, block, edges.exact_zero, tmin, tmax, unused) != 0;
}

}  // namespace twinray::bvh_leaf
