#pragma once
// The watertight ray-triangle test (core/intersect/triangle_watertight.h) on four triangles at once.
//
// Lane by lane this is the same IEEE float computation as the scalar test, operation for operation and in
// the same order (SSE mul/sub/add/div are correctly rounded like their scalar forms, and the build disables
// FMA contraction), so every lane yields bit-identical t, u, v and the bvh keeps matching the brute-force
// oracle exactly. The scalar test's one data-dependent detour, the double-precision re-evaluation when an
// edge function is exactly 0 (a ray through an edge or vertex), is taken by handing those rare lanes to the
// scalar test itself, so the fill rule lives in one place.

#include "backends/bvh/primitive_store.h"
#include "core/intersect/triangle_watertight.h"

#include <xmmintrin.h>

#include <cstdint>

namespace twinray {

struct alignas(16) BlockHits {
  float t[kTriangleBlockLanes], u[kTriangleBlockLanes], v[kTriangleBlockLanes];
};

// Tests the lanes of `block` set in `lanes` (bit i = lane i). Returns the mask of lanes hit within
// [tmin, tmax] and their t, u, v in `out`.
[[gnu::always_inline]] inline unsigned intersect_triangle_block(const TriangleRay& ray, const TriangleBlock& block, unsigned lanes,
                                         float tmin, float tmax, BlockHits& out) {
  const auto row = [&](int vert, int axis) { return _mm_load_ps(block.v[vert][axis]); };
  const __m128 ox = _mm_set1_ps(ray.ox), oy = _mm_set1_ps(ray.oy), oz = _mm_set1_ps(ray.oz);
  const __m128 sx = _mm_set1_ps(ray.sx), sy = _mm_set1_ps(ray.sy), sz = _mm_set1_ps(ray.sz);

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

  const __m128 zero = _mm_setzero_ps();
  const unsigned exact_zero = static_cast<unsigned>(_mm_movemask_ps(
                                  _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(u, zero), _mm_cmpeq_ps(v, zero)),
                                            _mm_cmpeq_ps(w, zero)))) & lanes;
  const __m128 any_negative = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(u, zero), _mm_cmplt_ps(v, zero)), _mm_cmplt_ps(w, zero));
  const __m128 any_positive = _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(u, zero), _mm_cmpgt_ps(v, zero)), _mm_cmpgt_ps(w, zero));
  const unsigned mixed_signs = static_cast<unsigned>(_mm_movemask_ps(_mm_and_ps(any_negative, any_positive)));
  unsigned candidates = lanes & ~exact_zero & ~mixed_signs;

  unsigned hits = 0;
  if (candidates != 0) {
    const __m128 det = _mm_add_ps(_mm_add_ps(u, v), w);
    const __m128 inv_det = _mm_div_ps(_mm_set1_ps(1.0f), det);
    const __m128 az = _mm_mul_ps(sz, a_z), bz = _mm_mul_ps(sz, b_z), cz = _mm_mul_ps(sz, c_z);
    const __m128 t = _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(u, az), _mm_mul_ps(v, bz)), _mm_mul_ps(w, cz)), inv_det);
    // Ordered comparisons: a NaN t (overflowing coordinates) is never a hit, as in the scalar test.
    const __m128 accept = _mm_and_ps(_mm_cmpneq_ps(det, zero),
                                     _mm_and_ps(_mm_cmpge_ps(t, _mm_set1_ps(tmin)), _mm_cmple_ps(t, _mm_set1_ps(tmax))));
    hits = candidates & static_cast<unsigned>(_mm_movemask_ps(accept));
    if (hits != 0) {
      _mm_store_ps(out.t, t);
      _mm_store_ps(out.u, _mm_mul_ps(v, inv_det));
      _mm_store_ps(out.v, _mm_mul_ps(w, inv_det));
    }
  }
  // Rays through an edge or a vertex: the scalar test decides them in double, with the fill rule.
  for (unsigned m = exact_zero; m != 0; m &= m - 1) {
    const unsigned lane = static_cast<unsigned>(__builtin_ctz(m));
    if (intersect_triangle(ray, block.vertex(0, lane), block.vertex(1, lane), block.vertex(2, lane), tmin, tmax,
                           out.t[lane], out.u[lane], out.v[lane]))
      hits |= 1u << lane;
  }
  return hits;
}

}  // namespace twinray
