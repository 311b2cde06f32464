#pragma once
// The watertight ray-triangle test (core/intersect/triangle_watertight.h) on four triangles at once.
//
// Lane by lane the edge test is the same IEEE float computation as the scalar test, operation for operation
// and in the same order (SSE mul/sub/add are correctly rounded like their scalar forms, and the build
// disables FMA contraction), so every lane makes the same hit decision. The scalar test's one data-dependent
// detour, the double-precision re-evaluation when an edge function is exactly 0 (a ray through an edge or
// vertex), is taken by handing those rare lanes to the scalar test itself, so the fill rule lives in one
// place. The reported t, u, v of a lane the edge test accepts come from the same function as the scalar
// test's (triangle_refine.h: correctly rounded), so the bvh keeps matching the brute-force oracle bit for bit.

#include "backends/bvh/primitive_store.h"
#include "core/intersect/triangle_watertight.h"

#include <xmmintrin.h>

#include <cstdint>

namespace twinray {

struct alignas(16) BlockHits {
  float t[kTriangleBlockLanes], u[kTriangleBlockLanes], v[kTriangleBlockLanes];
};

namespace triangle_block_detail {

// The exact path of the refinement for one lane, reading the block again: the hot path keeps no copy of the
// vertices alive for it.
[[gnu::cold, gnu::noinline]] inline bool exact_crossing_of_lane(const TriangleRay& ray, const TriangleBlock& block,
                                                               unsigned lane, float& t, float& u, float& v) {
  return refine_detail::exact_crossing_of(ray.refine, block.vertex(0, lane), block.vertex(1, lane),
                                          block.vertex(2, lane), t, u, v);
}

using triangle_detail::Report;  // what the test reports for the lanes it hits (triangle_watertight.h)

// The lanes whose float edge functions cannot decide (an exact 0: a ray through an edge or a vertex; a NaN:
// overflow far out in float's range), decided by the scalar test in double with the fill rule. Rare, so kept
// out of line: inlined, the scalar test's double path made every kernel's hot loop longer.
template <Report kReport>
[[gnu::cold, gnu::noinline]] unsigned decide_in_double(const TriangleRay& ray, const TriangleBlock& block,
                                                       unsigned lanes, float tmin, float tmax, BlockHits& out) {
  unsigned hits = 0;
  for (unsigned m = lanes; m != 0; m &= m - 1) {
    const unsigned lane = static_cast<unsigned>(__builtin_ctz(m));
    if (triangle_detail::intersect<kReport>(ray, block.vertex(0, lane), block.vertex(1, lane), block.vertex(2, lane),
                                            tmin, tmax, out.t[lane], out.u[lane], out.v[lane]))
      hits |= 1u << lane;
  }
  return hits;
}

// What the float edge test says of the lanes in `lanes`: those it accepts (`candidates`), and those whose
// edge functions cannot decide (`exact_zero`, for decide_in_double).
struct EdgeLanes {
  unsigned candidates, exact_zero;
};

// The three edge functions of the watertight test for the block's four lanes, in float (triangle_watertight.h:
// the vertices relative to the origin, sheared so that the ray runs along +z).
struct EdgeFunctions {
  __m128 u, v, w;
};

[[gnu::always_inline]] inline EdgeFunctions edge_functions(const TriangleRay& ray, const TriangleBlock& block) {
  const auto row = [&](int vert, std::ptrdiff_t axis) { return _mm_load_ps(block.v[vert][axis]); };
  const __m128 ox = _mm_set1_ps(ray.ox), oy = _mm_set1_ps(ray.oy), oz = _mm_set1_ps(ray.oz);
  const __m128 sx = _mm_set1_ps(ray.sx), sy = _mm_set1_ps(ray.sy);

  const __m128 a_z = _mm_sub_ps(row(0, ray.kz), oz);
  const __m128 b_z = _mm_sub_ps(row(1, ray.kz), oz);
  const __m128 c_z = _mm_sub_ps(row(2, ray.kz), oz);
  const __m128 ax = _mm_sub_ps(_mm_sub_ps(row(0, ray.kx), ox), _mm_mul_ps(sx, a_z));
  const __m128 ay = _mm_sub_ps(_mm_sub_ps(row(0, ray.ky), oy), _mm_mul_ps(sy, a_z));
  const __m128 bx = _mm_sub_ps(_mm_sub_ps(row(1, ray.kx), ox), _mm_mul_ps(sx, b_z));
  const __m128 by = _mm_sub_ps(_mm_sub_ps(row(1, ray.ky), oy), _mm_mul_ps(sy, b_z));
  const __m128 cx = _mm_sub_ps(_mm_sub_ps(row(2, ray.kx), ox), _mm_mul_ps(sx, c_z));
  const __m128 cy = _mm_sub_ps(_mm_sub_ps(row(2, ray.ky), oy), _mm_mul_ps(sy, c_z));

  const __m128 u = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
  const __m128 v = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
  const __m128 w = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
  return {u, v, w};
}

[[gnu::always_inline]] inline EdgeLanes edge_test(const TriangleRay& ray, const TriangleBlock& block, unsigned lanes) {
  const EdgeFunctions e = edge_functions(ray, block);
  const __m128 u = e.u, v = e.v, w = e.w;

  // The scalar test's detour (triangle_detail::needs_double): an edge function exactly 0, or NaN (products
  // that overflowed, far out in float's range). Then the product u v w is 0 or NaN, which 0 < |u v w| rejects
  // (an ordered comparison: false for NaN), in four operations instead of ten. The converse fails only when
  // the product underflows (edge functions below about 2^-42 each, at which point the lanes' sheared
  // coordinates are below about 2^-21 of one unit from the ray): such a lane also goes to the scalar test,
  // which decides it the same way, only slower. An infinite product (overflow) passes, as infinite edge
  // functions did (they have the exact sign).
  const __m128 zero = _mm_setzero_ps();
  const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  const __m128 decided = _mm_cmplt_ps(zero, _mm_and_ps(_mm_mul_ps(_mm_mul_ps(u, v), w), magnitude));
  const unsigned exact_zero = ~static_cast<unsigned>(_mm_movemask_ps(decided)) & lanes;
  // Among the others (none 0 or NaN) the signs are mixed exactly when the sign bits differ.
  const unsigned mixed_signs =
      static_cast<unsigned>(_mm_movemask_ps(_mm_or_ps(_mm_xor_ps(u, v), _mm_xor_ps(u, w))));
  unsigned candidates = lanes & ~exact_zero & ~mixed_signs;
  return {candidates, exact_zero};
}

template <Report kReport, bool kDivisionFreeFirst = false>
[[gnu::always_inline]] inline unsigned intersect(const TriangleRay& ray, const TriangleBlock& block, unsigned lanes,
                                                 float tmin, float tmax, BlockHits& out) {
  const auto [candidates, exact_zero] = edge_test(ray, block, lanes);
  if ((candidates | exact_zero) == 0) return 0;  // the common case: the ray passes beside all four

  // The candidates' edge functions are non-zero, not NaN and of one sign, so their determinant is not 0: the
  // scalar test's parallel and in-plane cases all reach it through the detour.
  // The edge test has decided; t, u, v come from the refinement shared with the scalar test
  // (core/intersect/triangle_refine.h), one candidate lane at a time.
  unsigned hits = 0;
  for (unsigned m = candidates; m != 0; m &= m - 1) {
    const unsigned lane = static_cast<unsigned>(__builtin_ctz(m));
    const glm::vec3 p0 = block.vertex(0, lane), p1 = block.vertex(1, lane), p2 = block.vertex(2, lane);
    const auto exact = [&ray, &block, lane](float& te, float& ue, float& ve) {
      return exact_crossing_of_lane(ray, block, lane, te, ue, ve);
    };
    if constexpr (kReport == Report::kAny) {
      if (refine_detail::refine_in_interval<kDivisionFreeFirst>(ray.refine, p0, p1, p2, tmin, tmax, exact))
        return 1u << lane;
      continue;
    } else {
      if (!refine_detail::refine_t(ray.refine, p0, p1, p2, tmin, tmax, out.t[lane], exact)) continue;
      if constexpr (kReport == Report::kHit)
        refine_detail::refine_uv(ray.refine, p0, p1, p2, out.t[lane], out.u[lane], out.v[lane], nullptr, exact);
    }
    hits |= 1u << lane;
  }
  if (exact_zero != 0) hits |= decide_in_double<kReport>(ray, block, exact_zero, tmin, tmax, out);
  return hits;
}

}  // namespace triangle_block_detail

// Tests the lanes of `block` set in `lanes` (bit i = lane i). Returns the mask of lanes hit within
// [tmin, tmax] and their t, u, v in `out`.
[[gnu::always_inline]] inline unsigned intersect_triangle_block(const TriangleRay& ray, const TriangleBlock& block,
                                                                unsigned lanes, float tmin, float tmax, BlockHits& out) {
  return triangle_block_detail::intersect<triangle_block_detail::Report::kHit>(ray, block, lanes, tmin, tmax, out);
}

// Closest hit: calls `on_hit(lane, t, crossing)` for every lane hit within [tmin, tmax], t correctly rounded
// as above, and continues with the tmax it returns (the caller's closest t so far: the interval stays closed,
// so a tie still reaches the caller, whose order decides it). `crossing` is what the refinement of t computed
// (refine_detail::Crossing: e1, e2, e1 x e2, den), for the caller to keep if the lane is its best so far and
// give to triangle_block_hit_attributes at the end, which then need not compute it again; nullptr for a lane
// decided in double (a ray through an edge or vertex), whose attributes are computed from the block.
// kBehindFirst: see refine_detail::refine_t_kept_v (bvh8 passes true; a valid ray's tmin >= 0).
template <bool kBehindFirst = false, typename OnHit>
[[gnu::always_inline]] inline void intersect_triangle_block_closest(const TriangleRay& ray, const TriangleBlock& block,
                                                                    unsigned lanes, float tmin, float tmax,
                                                                    const OnHit& on_hit) {
  using namespace triangle_block_detail;
  const auto [candidates, exact_zero] = edge_test(ray, block, lanes);
  if ((candidates | exact_zero) == 0) return;
  for (unsigned m = candidates; m != 0; m &= m - 1) {
    const unsigned lane = static_cast<unsigned>(__builtin_ctz(m));
    refine_detail::Crossing crossing;
    float t;
    if (!refine_detail::refine_t<kBehindFirst>(ray.refine, block.vertex(0, lane), block.vertex(1, lane), block.vertex(2, lane), tmin,
                                 tmax, t, crossing, [&ray, &block, lane](float& te, float& ue, float& ve) {
                                   return exact_crossing_of_lane(ray, block, lane, te, ue, ve);
                                 }))
      continue;
    tmax = on_hit(lane, t, &crossing);
  }
  if (exact_zero != 0) {
    BlockHits found;
    for (unsigned m = decide_in_double<Report::kT>(ray, block, exact_zero, tmin, tmax, found); m != 0; m &= m - 1) {
      const unsigned lane = static_cast<unsigned>(__builtin_ctz(m));
      tmax = on_hit(lane, found.t[lane], static_cast<const refine_detail::Crossing*>(nullptr));
    }
  }
}

// u, v and the geometric normal of lane `lane`'s crossing at the t a block test reported for it (what
// triangle_hit_attributes gives for the same triangle): a closest-hit traversal's winner. From `kept`, the
// crossing intersect_triangle_block_closest gave with that t, when there is one; from the block otherwise.
[[gnu::always_inline]] inline void triangle_block_hit_attributes(const TriangleRay& ray, const TriangleBlock& block,
                                                                 unsigned lane, float t, float& u, float& v,
                                                                 glm::vec3& ng,
                                                                 const refine_detail::Crossing* kept = nullptr) {
  const auto exact = [&ray, &block, lane](float& te, float& ue, float& ve) {
    return triangle_block_detail::exact_crossing_of_lane(ray, block, lane, te, ue, ve);
  };
  if (kept != nullptr) {
    refine_detail::refine_uv_kept(ray.refine, *kept, t, u, v, &ng, exact);
    return;
  }
  refine_detail::refine_uv(ray.refine, block.vertex(0, lane), block.vertex(1, lane), block.vertex(2, lane), t, u, v,
                           &ng, exact);
}

// Whether any lane is hit within [tmin, tmax] (a non-zero mask of one of them): any-hit queries. A crossing
// whose t interval lies inside [tmin, tmax] counts without its rounding being certified.
// kDivisionFreeFirst: see refine_detail::refine_in_interval_v (bvh passes true; bvh8's any-hit leaves run their
// own copy of this loop, block_occluded in backends/wide/wide_traversal.inl, deciding by the sign of t).
template <bool kDivisionFreeFirst = false>
[[gnu::always_inline]] inline unsigned intersect_triangle_block_any(const TriangleRay& ray, const TriangleBlock& block,
                                                                    unsigned lanes, float tmin, float tmax) {
  BlockHits unused;
  return triangle_block_detail::intersect<triangle_block_detail::Report::kAny, kDivisionFreeFirst>(
      ray, block, lanes, tmin, tmax, unused);
}

}  // namespace twinray
