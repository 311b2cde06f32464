// The wide traversal kernels on AVX-512 (F, VL, DQ, BW): the AVX2 slab test on 256-bit registers with the
// comparison straight into a mask register (an 8-wide node fills 256 bits, so no wider rows).
// See backends/simd/isa.h for how the instruction sets are chosen.

#include "backends/wide/wide_kernels.h"

#include "backends/bvh/ray_box.h"
#include "backends/bvh/triangle_block.h"
#include "backends/wide/wide_octant_rows.h"
#include "backends/wide/wide_push_order.h"
#include "backends/wide/wide_ray_check.h"
#include "core/intersect/sphere_robust.h"
#include "core/intersect/triangle_watertight.h"

#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace twinray::wide_avx512 {

#define TWINRAY_KERNEL TWINRAY_TARGET_AVX512

TWINRAY_KERNEL inline unsigned cmp_le_mask(__m256 a, __m256 b) {
  return static_cast<unsigned>(_mm256_cmp_ps_mask(a, b, _CMP_LE_OQ));
}
TWINRAY_KERNEL inline unsigned sign_mask(__m256i v) {
  return static_cast<unsigned>(_mm256_movepi32_mask(v));
}

// The ray's per-axis values as scalars, read by {1to8} broadcast operands (wide_box_test_256.inl).
inline constexpr bool kWideSplatScalars = true;
using WideSplat = float;
TWINRAY_KERNEL inline float make_splat(float x) { return x; }
TWINRAY_KERNEL inline __m256 splat(const float& x) { return _mm256_set1_ps(x); }

#include "backends/wide/wide_box_test_256.inl"
#include "backends/wide/wide_traversal.inl"
#undef TWINRAY_KERNEL

}  // namespace twinray::wide_avx512
