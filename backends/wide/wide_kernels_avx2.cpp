// The wide traversal kernels on AVX2: each node's eight boxes in one 256-bit register per plane.
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

namespace twinray::wide_avx2 {

#define TWINRAY_KERNEL TWINRAY_TARGET_AVX2

TWINRAY_KERNEL inline unsigned cmp_le_mask(__m256 a, __m256 b) {
  return static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(a, b, _CMP_LE_OQ)));
}
TWINRAY_KERNEL inline unsigned sign_mask(__m256i v) {
  return static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(v)));
}

// The ray's per-axis values as whole broadcast vectors, read as memory operands (wide_box_test_256.inl).
inline constexpr bool kWideSplatScalars = false;
using WideSplat = __m256;
TWINRAY_KERNEL inline __m256 make_splat(float x) { return _mm256_set1_ps(x); }
TWINRAY_KERNEL inline __m256 splat(const __m256& v) { return v; }

#include "backends/wide/wide_box_test_256.inl"
#include "backends/wide/wide_traversal.inl"
#undef TWINRAY_KERNEL

}  // namespace twinray::wide_avx2
