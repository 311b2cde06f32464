#pragma once
// is_valid_ray (core/geometry/ray.h) on the ray's two 16-byte halves at once: the same conditions, each a
// lane of an SSE2 comparison. Every bvh8 kernel checks its ray first (an invalid ray must not sweep the
// tree), and the scalar form's chain of branches cost about 35 instructions a query, 5% of a shadow ray's
// any-hit query on the dragon (docs/bvh-backend.md, "Any-hit, eighth round").

#include "core/geometry/ray.h"

#include <emmintrin.h>

#include <cstddef>
#include <limits>

namespace twinray {

inline bool wide_ray_is_valid(const Ray& ray) {
  static_assert(offsetof(Ray, tmin) == 12 && offsetof(Ray, dir) == 16 && offsetof(Ray, tmax) == 28,
                "the two halves: (org, tmin) and (dir, tmax)");
  const __m128 first = _mm_loadu_ps(&ray.org.x);   // org.x, org.y, org.z, tmin
  const __m128 second = _mm_loadu_ps(&ray.dir.x);  // dir.x, dir.y, dir.z, tmax
  const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  const __m128 zero = _mm_setzero_ps();
  // Finite: |x| < inf, which NaN fails. Every lane of the first half (origin and tmin), the direction's
  // three of the second.
  const unsigned finite_first = static_cast<unsigned>(_mm_movemask_ps(_mm_cmplt_ps(_mm_and_ps(first, magnitude), inf)));
  const unsigned finite_second =
      static_cast<unsigned>(_mm_movemask_ps(_mm_cmplt_ps(_mm_and_ps(second, magnitude), inf)));
  // Lane 3: 0 <= tmin and tmin <= tmax (both false for a NaN bound).
  const unsigned interval =
      static_cast<unsigned>(_mm_movemask_ps(_mm_and_ps(_mm_cmpge_ps(first, zero), _mm_cmple_ps(first, second))));
  // A direction component != 0 (true for NaN too, which the finite lanes already exclude).
  const unsigned nonzero = static_cast<unsigned>(_mm_movemask_ps(_mm_cmpneq_ps(second, zero)));
  const unsigned required = finite_first | (finite_second << 4) | (interval << 8);
  return (required & 0x87Fu) == 0x87Fu && (nonzero & 7u) != 0;
}

}  // namespace twinray
