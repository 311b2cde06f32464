// The wide traversal kernels on AVX-512 (F, VL, DQ, BW): the AVX2 slab test on 256-bit registers with the
// comparison straight into a mask register (an 8-wide node fills 256 bits, so no wider rows).
// See backends/simd/isa.h for how the instruction sets are chosen.

#include "backends/wide/wide_kernels.h"

#include "backends/bvh/ray_box.h"
#include "backends/bvh/cull_interval.h"
#include "backends/bvh/triangle_block.h"
#include "core/intersect/sphere_robust.h"
#include "core/intersect/triangle_watertight.h"

#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace twinray::wide_avx512 {

#define TWINRAY_KERNEL TWINRAY_TARGET_AVX512

// The ray as the slab test needs it; see wide_kernels_sse2.cpp.
struct WideBoxRay {
  __m256 org[3], inv[3];
  std::size_t near_row[3], far_row[3];

  TWINRAY_KERNEL explicit WideBoxRay(const Ray& ray) {
    for (int a = 0; a < 3; ++a) {
      const float inv_dir = 1.0f / ray.dir[a];
      org[a] = _mm256_set1_ps(ray.org[a]);
      inv[a] = _mm256_set1_ps(inv_dir);
      const bool negative = std::signbit(inv_dir);
      near_row[a] = negative ? WideNode::hi_row(a) : WideNode::lo_row(a);
      far_row[a] = negative ? WideNode::lo_row(a) : WideNode::hi_row(a);
    }
  }
};

// Ize's robust slab test on all eight boxes (see wide_kernels_sse2.cpp for the NaN handling).
TWINRAY_KERNEL inline unsigned test_boxes(const WideNode& node, const WideBoxRay& r, float tmin, float tmax,
                                          float* entry) {
  const float* rows = &node.lo[0][0];
  __m256 t0 = _mm256_set1_ps(tmin), t1 = _mm256_set1_ps(tmax);
  const __m256 scale = _mm256_set1_ps(kSlabFarScale);
  for (int a = 0; a < 3; ++a) {
    const __m256 t_near = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(rows + r.near_row[a]), r.org[a]), r.inv[a]);
    const __m256 t_far =
        _mm256_mul_ps(_mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(rows + r.far_row[a]), r.org[a]), r.inv[a]), scale);
    t0 = _mm256_max_ps(t_near, t0);
    t1 = _mm256_min_ps(t_far, t1);
  }
  _mm256_store_ps(entry, t0);
  return static_cast<unsigned>(_mm256_cmp_ps_mask(t0, t1, _CMP_LE_OQ));
}

TWINRAY_KERNEL inline unsigned leaf_children(const WideNode& node) {
  return static_cast<unsigned>(_mm256_movepi32_mask(_mm256_load_si256(reinterpret_cast<const __m256i*>(node.child))));
}

#include "backends/wide/wide_traversal.inl"
#undef TWINRAY_KERNEL

WideKernels kernels(bool triangles, bool spheres) {
  if (triangles && spheres) return {&wide_intersect<true, true>, &wide_occluded<true, true>};
  if (spheres) return {&wide_intersect<false, true>, &wide_occluded<false, true>};
  return {&wide_intersect<true, false>, &wide_occluded<true, false>};
}

}  // namespace twinray::wide_avx512
