#pragma once
// Robust ray-box (slab) test for BVH traversal.
//
// Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013, with the error moved to where the traversal needs it:
// the near distance is scaled *down* and the far distance up, so that each is a bound of the exact one and
// the boxes can be tested against the ray's own interval [tmin, tmax], unwidened. Every tree (bvh, bvh8)
// uses these two scales, so all of them cull alike.
//
// What must not be culled. A primitive counts when its *correctly rounded* t lies in [tmin, tmax]
// (core/geometry/ray.h, core/intersect/triangle_refine.h), and a closest-hit traversal keeps tmax at the
// best t so far with the interval closed, so that a later primitive at the same rounded t still reaches the
// tie rule (lowest geom_id, then prim_id). So a box must be entered whenever it holds a point of the ray
// whose exact t rounds into [tmin, tmax], i.e. lies in [T0, T1] with T1 = tmax + ulp+(tmax) / 2 and
// T0 = tmin - ulp-(tmin) / 2 (the midpoints to the floats beside them; ulp+ and ulp- the gaps above and
// below). No float lies in (tmax, T1] or in [T0, tmin).
//
// The two bounds. With u = 2^-24 and every rounding a factor (1 + d_i), |d_i| <= u (no underflow or
// overflow: a slab distance is 0 or of magnitude at least 2^-126, and the reciprocals are finite, as in
// Ize's analysis and as before this change):
//  - near = fl(fl(plane - org) * fl(fl(1 / dir) * kSlabNearScale)): four roundings and kSlabNearScale =
//    1 - 4u exactly, so near = exact (1 - 4u) prod(1 + d_i) <= exact (1 - 4u)(1 + u)^4 =
//    exact (1 - 10u^2 - ...) <= exact for exact >= 0; for exact < 0, near <= 0 (the sign is kept).
//  - far = fl(fl(plane - org) * fl(fl(1 / dir) * kSlabFarScale)): kSlabFarScale = 1 + 6u exactly, so
//    far >= exact (1 + 6u)(1 - u)^4 = exact (1 + 2u - 18u^2 + ...) >= exact for exact >= 0.
// Take a box holding a point of the ray at exact t_p in [T0, T1], so exact near_i <= t_p <= exact far_j for
// all axes i, j. Then: near_i <= max(exact near_i, 0) <= T1, and near_i is a float, so near_i <= tmax.
// far_j >= exact far_j >= t_p >= T0 when tmin > 0 (T0 > 0), so far_j >= tmin, a float; when tmin = 0,
// exact far_j >= t_p >= -2^-150, so exact far_j >= 0 (no underflow) and far_j >= 0 = tmin. And near_i <=
// max(exact near_i, 0) <= exact far_j <= far_j. Hence max(near_i, tmin) <= min(far_j, tmax) over all axes:
// the box is entered, against the ray's own [tmin, tmax]. Before the tenth round the near distance was
// unscaled (three roundings, up to (1 + u)^3 above the exact one) and the interval was widened by 2^-21
// instead (4 to 8 ulps at tmax); see the tenth round in docs/bvh-backend.md.
//
// Zero direction components: inv_dir = 1/(+-0) = +-inf (scaled, still +-inf), so distances are +-inf and
// the slab is either all or nothing, as it should be. The one NaN, 0 * inf, appears when the origin lies
// exactly on a slab plane of an axis the ray is parallel to: the ray then runs inside the (closed) slab, so
// it must not constrain the interval. _mm_max_ps(a, b) and _mm_min_ps(a, b) return b when either is NaN, so
// max(candidate, tmin) and min(candidate, tmax) drop a NaN candidate: the NaN slab is treated as containing
// the whole ray. Conservative, never a culled hit. (Choosing the near plane by the sign of the direction,
// rather than taking min/max of the two plane distances, matters here: with min/max, an origin on the far
// plane would turn (-inf, NaN) into an empty interval.)
//
// The test runs on SSE2 lanes x, y, z; lane 3 reads the node's integer field and is neutralised by a NaN
// in the reciprocals' lane 3, which the same NaN rule turns into "no constraint".
//
// The child-pair test exists twice: two SSE2 tests, and one AVX test of both boxes side by side; the
// traversal kernels pick one per instruction set (bvh_kernels.h, backends/simd/isa.h).

#include "backends/bvh/bvh_node.h"
#include "backends/simd/isa.h"
#include "core/geometry/ray.h"

#include <emmintrin.h>
#include <immintrin.h>

#include <cmath>
#include <limits>

namespace twinray {

// The scales of the reciprocal for the near and the far planes (derivation above): 1 - 4u and 1 + 6u, both
// exact in float. (1 + 6u is also 1 + 2 gamma(3) rounded up, Ize's far scale, the value it had before.)
inline constexpr float kSlabNearScale = 1.0f - 0x1p-22f;
inline constexpr float kSlabFarScale = 1.0f + 0x3p-23f;
static_assert(kSlabNearScale == 1.0f - 4.0f * 0x1p-24f && kSlabFarScale == 1.0f + 6.0f * 0x1p-24f);

struct BoxRay {
  __m128 org;          // (x, y, z, 0)
  __m128 inv_dir_near;  // (1/x, 1/y, 1/z, NaN) * kSlabNearScale, for the near planes; 1/(+-0) = +-inf
  __m128 inv_dir_far;   // the same * kSlabFarScale, for the far planes (see above and below)
  __m128 negative;     // all-ones lanes where the direction's sign bit is set (-0 included): near plane = hi

  BoxRay() = default;
  // Four lanes at once: one division for the three reciprocals (correctly rounded like three scalar ones),
  // the sign masks by an arithmetic shift of the reciprocals' sign bits. Lane 3 divides 1 by a NaN, so it is
  // a (positive) NaN, and its mask is 0. Ray is (org, tmin, dir, tmax), so lane 3 of each load is masked.
  explicit BoxRay(const Ray& ray) {
    const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
    const __m128 nan_w = _mm_castsi128_ps(_mm_setr_epi32(0, 0, 0, 0x7fc00000));
    org = _mm_and_ps(_mm_loadu_ps(&ray.org.x), xyz);
    const __m128 inv_dir = _mm_div_ps(_mm_set1_ps(1.0f), _mm_or_ps(_mm_and_ps(_mm_loadu_ps(&ray.dir.x), xyz), nan_w));
    inv_dir_near = _mm_mul_ps(inv_dir, _mm_set1_ps(kSlabNearScale));
    inv_dir_far = _mm_mul_ps(inv_dir, _mm_set1_ps(kSlabFarScale));
    negative = _mm_castsi128_ps(_mm_srai_epi32(_mm_castps_si128(inv_dir), 31));
  }
};

// Both distances are (plane - org) * (inv_dir * scale), the scaled reciprocal rounded once per ray, rather
// than ((plane - org) * inv_dir) * scale: both are the exact distance times the scale times four rounding
// factors (1 + d_i), |d_i| <= 2^-24 (the difference, the reciprocal, the product and the product with the
// scale, in either order), which is all the bounds above count (as in the wide kernels,
// backends/wide/wide_kernels_sse2.cpp); an infinite reciprocal stays infinite. No product per box.

// True when the ray overlaps the node's box within [tmin, tmax] (closed); `entry` is where it enters.
[[gnu::always_inline]] inline bool intersect_box(const BvhNode& node, const BoxRay& r, float tmin, float tmax, float& entry) {
  // 16-byte loads: (lo, offset) and (hi, count); the integer lane is neutralised (see above).
  const __m128 lo = _mm_load_ps(&node.lo.x);
  const __m128 hi = _mm_load_ps(&node.hi.x);
  const __m128 near_plane = _mm_or_ps(_mm_and_ps(r.negative, hi), _mm_andnot_ps(r.negative, lo));
  const __m128 far_plane = _mm_or_ps(_mm_and_ps(r.negative, lo), _mm_andnot_ps(r.negative, hi));
  const __m128 t_near = _mm_mul_ps(_mm_sub_ps(near_plane, r.org), r.inv_dir_near);
  const __m128 t_far = _mm_mul_ps(_mm_sub_ps(far_plane, r.org), r.inv_dir_far);
  // Operand order matters: the NaN-free bound is the second operand (see above).
  __m128 t0 = _mm_max_ps(t_near, _mm_set1_ps(tmin));
  __m128 t1 = _mm_min_ps(t_far, _mm_set1_ps(tmax));
  // Horizontal max / min over the four (now NaN-free) lanes.
  t0 = _mm_max_ps(t0, _mm_movehl_ps(t0, t0));
  t0 = _mm_max_ss(t0, _mm_shuffle_ps(t0, t0, 1));
  t1 = _mm_min_ps(t1, _mm_movehl_ps(t1, t1));
  t1 = _mm_min_ss(t1, _mm_shuffle_ps(t1, t1, 1));
  entry = _mm_cvtss_f32(t0);
  return entry <= _mm_cvtss_f32(t1);
}

// The ray of a child-pair test, with the interval the boxes are tested against. Built once per query; the
// traversal calls set_tmax when the closest hit so far moves the end of the interval.
struct BoxPairRaySse2 {
  static constexpr unsigned kFirstHit = 1u, kSecondHit = 2u;  // the bits of intersect_box_pair_sse2's result
  BoxRay ray;
  float tmin, tmax;
  BoxPairRaySse2(const BoxRay& r, float t0, float t1) : ray(r), tmin(t0), tmax(t1) {}
  void set_tmax(float t) { tmax = t; }
};

// Both children of an interior node: two single tests. Returns a bit mask: kFirstHit when a is hit,
// kSecondHit when b is hit.
[[gnu::always_inline]] inline unsigned intersect_box_pair_sse2(const BvhNode& a, const BvhNode& b,
                                                               const BoxPairRaySse2& r, float& entry_a,
                                                               float& entry_b) {
  return (intersect_box(a, r.ray, r.tmin, r.tmax, entry_a) ? 1u : 0u) |
         (intersect_box(b, r.ray, r.tmin, r.tmax, entry_b) ? 2u : 0u);
}

// The same for the AVX test: the ray's vectors in both 128-bit halves and the interval in all eight lanes,
// broadcast once per query rather than once per node (the compiler does not keep them in registers across
// the traversal loop), so the node test reads them as memory operands.
struct BoxPairRayAvx2 {
  // The bits of intersect_box_pair_avx2's result: the sign bits of lane 0 of each half, as movemask gives
  // them (no instructions to move them to bits 0 and 1).
  static constexpr unsigned kFirstHit = 1u, kSecondHit = 16u;
  __m256 org, inv_dir_near, inv_dir_far, negative, tmin, tmax;
  [[gnu::always_inline]] TWINRAY_TARGET_AVX2 BoxPairRayAvx2(const BoxRay& r, float t0, float t1)
      : org(_mm256_set_m128(r.org, r.org)),
        inv_dir_near(_mm256_set_m128(r.inv_dir_near, r.inv_dir_near)),
        inv_dir_far(_mm256_set_m128(r.inv_dir_far, r.inv_dir_far)),
        negative(_mm256_set_m128(r.negative, r.negative)),
        tmin(_mm256_set1_ps(t0)),
        tmax(_mm256_set1_ps(t1)) {}
  [[gnu::always_inline]] TWINRAY_TARGET_AVX2 void set_tmax(float t) { tmax = _mm256_set1_ps(t); }
};

// Both children at once: the test above, lane for lane, on the two boxes side by side in one AVX register
// (low half: a, high half: b), so the entries are bit-identical to two single tests. Returns kFirstHit and
// kSecondHit of BoxPairRayAvx2.
[[gnu::always_inline]] TWINRAY_TARGET_AVX2 inline unsigned intersect_box_pair_avx2(const BvhNode& a, const BvhNode& b,
                                                                                  const BoxPairRayAvx2& r,
                                                                                  float& entry_a, float& entry_b) {
  const __m256 lo = _mm256_set_m128(_mm_load_ps(&b.lo.x), _mm_load_ps(&a.lo.x));
  const __m256 hi = _mm256_set_m128(_mm_load_ps(&b.hi.x), _mm_load_ps(&a.hi.x));
  const __m256 near_plane = _mm256_blendv_ps(lo, hi, r.negative);
  const __m256 far_plane = _mm256_blendv_ps(hi, lo, r.negative);
  const __m256 t_near = _mm256_mul_ps(_mm256_sub_ps(near_plane, r.org), r.inv_dir_near);
  const __m256 t_far = _mm256_mul_ps(_mm256_sub_ps(far_plane, r.org), r.inv_dir_far);
  // Operand order matters: the NaN-free bound is the second operand (see above).
  __m256 t0 = _mm256_max_ps(t_near, r.tmin);
  __m256 t1 = _mm256_min_ps(t_far, r.tmax);
  // Horizontal max / min within each 128-bit half.
  t0 = _mm256_max_ps(t0, _mm256_permute_ps(t0, _MM_SHUFFLE(1, 0, 3, 2)));
  t0 = _mm256_max_ps(t0, _mm256_permute_ps(t0, _MM_SHUFFLE(2, 3, 0, 1)));
  t1 = _mm256_min_ps(t1, _mm256_permute_ps(t1, _MM_SHUFFLE(1, 0, 3, 2)));
  t1 = _mm256_min_ps(t1, _mm256_permute_ps(t1, _MM_SHUFFLE(2, 3, 0, 1)));
  entry_a = _mm256_cvtss_f32(t0);
  entry_b = _mm_cvtss_f32(_mm256_extractf128_ps(t0, 1));
  const unsigned hit = static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ)));
  return hit & (BoxPairRayAvx2::kFirstHit | BoxPairRayAvx2::kSecondHit);
}

}  // namespace twinray
