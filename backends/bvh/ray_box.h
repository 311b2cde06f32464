#pragma once
// Robust ray-box (slab) test for BVH traversal.
//
// Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013. The slab distances (plane - org) * inv_dir are each
// computed with a relative error of at most gamma(3) (the subtraction, the product, and the reciprocal
// computed once per ray), gamma(n) = n eps / (1 - n eps), eps = 2^-24. Scaling every far distance by
// 1 + 2 gamma(3) therefore makes the test conservative: a box the exact ray touches is never culled, so
// the watertight triangle test never loses a hit to the BVH.
//
// Zero direction components: inv_dir = 1/(+-0) = +-inf, so distances are +-inf and the slab is either
// all or nothing, as it should be. The one NaN, 0 * inf, appears when the origin lies exactly on a slab
// plane of an axis the ray is parallel to: the ray then runs inside the (closed) slab, so it must not
// constrain the interval. _mm_max_ps(a, b) and _mm_min_ps(a, b) return b when either is NaN, so
// max(candidate, tmin) and min(candidate, tmax) drop a NaN candidate: the NaN slab is treated as containing
// the whole ray. Conservative, never a culled hit. (Choosing the near plane by the sign of the direction,
// rather than taking min/max of the two plane distances, matters here: with min/max, an origin on the far
// plane would turn (-inf, NaN) into an empty interval.)
//
// The test runs on SSE2 lanes x, y, z; lane 3 reads the node's integer field and is neutralised by a NaN
// in inv_dir's lane 3, which the same NaN rule turns into "no constraint".

#include "backends/bvh/bvh_node.h"
#include "core/geometry/ray.h"

#include <emmintrin.h>

#include <cmath>
#include <limits>

namespace twinray {

// 1 + 2 gamma(3), rounded up, with eps = 2^-24.
inline constexpr float kSlabFarScale = static_cast<float>(1.0 + 2.0 * (3.0 * 0x1p-24) / (1.0 - 3.0 * 0x1p-24)) *
                                       (1.0f + 0x1p-23f);

struct BoxRay {
  __m128 org;       // (x, y, z, 0)
  __m128 inv_dir;   // (1/x, 1/y, 1/z, NaN); 1/(+-0) = +-inf
  __m128 negative;  // all-ones lanes where the direction's sign bit is set (-0 included): near plane = hi

  explicit BoxRay(const Ray& ray) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float ix = 1.0f / ray.dir.x, iy = 1.0f / ray.dir.y, iz = 1.0f / ray.dir.z;
    org = _mm_setr_ps(ray.org.x, ray.org.y, ray.org.z, 0.0f);
    inv_dir = _mm_setr_ps(ix, iy, iz, nan);
    const auto mask = [](float v) { return std::signbit(v) ? -1 : 0; };
    negative = _mm_castsi128_ps(_mm_setr_epi32(mask(ix), mask(iy), mask(iz), 0));
  }
};

// True when the ray overlaps the node's box within [tmin, tmax] (closed); `entry` is where it enters.
inline bool intersect_box(const BvhNode& node, const BoxRay& r, float tmin, float tmax, float& entry) {
  // 16-byte loads: (lo, offset) and (hi, count); the integer lane is neutralised (see above).
  const __m128 lo = _mm_load_ps(&node.lo.x);
  const __m128 hi = _mm_load_ps(&node.hi.x);
  const __m128 near_plane = _mm_or_ps(_mm_and_ps(r.negative, hi), _mm_andnot_ps(r.negative, lo));
  const __m128 far_plane = _mm_or_ps(_mm_and_ps(r.negative, lo), _mm_andnot_ps(r.negative, hi));
  const __m128 t_near = _mm_mul_ps(_mm_sub_ps(near_plane, r.org), r.inv_dir);
  const __m128 t_far =
      _mm_mul_ps(_mm_mul_ps(_mm_sub_ps(far_plane, r.org), r.inv_dir), _mm_set1_ps(kSlabFarScale));
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

}  // namespace twinray
