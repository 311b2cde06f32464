// The wide traversal kernels on SSE2 (any x86-64 CPU): each node's eight boxes as two groups of four.
// See backends/simd/isa.h for how the instruction sets are chosen.

#include "backends/wide/wide_kernels.h"

#include "backends/bvh/ray_box.h"
#include "backends/bvh/triangle_block.h"
#include "backends/wide/wide_octant_rows.h"
#include "backends/wide/wide_ray_check.h"
#include "core/intersect/sphere_robust.h"
#include "core/intersect/triangle_watertight.h"

#include <emmintrin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace twinray::wide_sse2 {

#define TWINRAY_KERNEL

// The ray in double for the refinement: set_ray's scalar conversions (the AVX kernels convert each half of
// the ray at once, wide_box_test_256.inl).
inline void set_refine_ray(refine_detail::RefineRay& r, const Ray& ray) { refine_detail::set_ray(r, ray.org, ray.dir); }

// Vertex `vert` of lane `lane` of a block as the refinement's doubles (refine_detail::load's conversions).
inline refine_detail::Vec4 block_vertex(const TriangleBlock& block, unsigned vert, unsigned lane) {
  return refine_detail::load(block.vertex(vert, lane));
}

// The ray as the slab test needs it: origin and reciprocal direction broadcast, and per axis the row
// offsets (WideNode::lo_row / hi_row) of the near and far planes, chosen by the sign of the reciprocal (-0
// included) as in ray_box.h. The reciprocals come from one vector division (each lane the same IEEE
// quotient as a scalar division) and the row offsets from the table of the three sign bits
// (wide_octant_rows.h): no branch on the direction's signs, which incoherent rays mispredict.
struct WideBoxRay {
  __m128 org[3];
  __m128 inv[3];      // the reciprocal scaled by kSlabNearScale, for the near planes (ray_box.h)
  __m128 inv_far[3];  // the reciprocal scaled by kSlabFarScale, for the far planes (see below)
  WideOctantRows rows;

  explicit WideBoxRay(const Ray& ray) {
    const __m128 inv_dir = _mm_div_ps(_mm_set1_ps(1.0f), _mm_setr_ps(ray.dir.x, ray.dir.y, ray.dir.z, 1.0f));
    alignas(16) float inv_s[4], inv_far_s[4];
    _mm_store_ps(inv_s, _mm_mul_ps(inv_dir, _mm_set1_ps(kSlabNearScale)));
    _mm_store_ps(inv_far_s, _mm_mul_ps(inv_dir, _mm_set1_ps(kSlabFarScale)));
    for (int a = 0; a < 3; ++a) {
      org[a] = _mm_set1_ps(ray.org[a]);
      inv[a] = _mm_set1_ps(inv_s[a]);
      inv_far[a] = _mm_set1_ps(inv_far_s[a]);
    }
    rows = kWideOctantRows[static_cast<unsigned>(_mm_movemask_ps(inv_dir)) & 7u];
  }

  // Tells the compiler the vectors may have changed in memory (wide_traversal.inl, reread_vectors).
  void reread() { asm("" : "+m"(org), "+m"(inv), "+m"(inv_far)); }
};

// Ize's robust slab test (ray_box.h) on four boxes: columns [col, col + 4) of the node's rows. The near and
// far values of each axis are folded into [tmin, tmax] one axis at a time with the NaN-free bound as the
// second operand of max / min, so a 0 * inf NaN drops out exactly as in the binary test.
//
// Both distances are (plane - org) * (1/dir * scale) with the scaled reciprocal rounded once per ray (as in
// ray_box.h): the exact distance times the scale times four rounding factors (1 + d_i), |d_i| <= 2^-24 (the
// difference, the reciprocal, the product with the scale and the product), which is what ray_box.h's
// bounds count: the near distance is at most the exact one, the far distance at least, so the boxes are
// tested against the ray's own [tmin, tmax]. An infinite reciprocal stays infinite.
inline unsigned test_four(const float* rows, const WideBoxRay& r, std::size_t col, __m128 tmin, __m128 tmax,
                          float* entry) {
  __m128 t0 = tmin, t1 = tmax;
  for (int a = 0; a < 3; ++a) {
    const __m128 t_near = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(rows + r.rows.near_row[a] + col), r.org[a]), r.inv[a]);
    const __m128 t_far = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(rows + r.rows.far_row[a] + col), r.org[a]), r.inv_far[a]);
    t0 = _mm_max_ps(t_near, t0);
    t1 = _mm_min_ps(t_far, t1);
  }
  _mm_store_ps(entry + col, t0);
  return static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(t0, t1)));
}

// Bit s set when child slot s's box is hit within [tmin, tmax]; entry[s] is where the ray enters it.
inline unsigned test_boxes(const WideNode& node, const WideBoxRay& r, float tmin, float tmax, float* entry) {
  const __m128 t0 = _mm_set1_ps(tmin), t1 = _mm_set1_ps(tmax);
  return test_four(&node.lo[0][0], r, 0, t0, t1, entry) | (test_four(&node.lo[0][0], r, 4, t0, t1, entry) << 4);
}

// The any-hit traversal's fixed interval (the AVX2 and AVX-512 kernels keep it as vectors, wide_box_test_256.inl).
struct WideBoxInterval {
  float tmin, tmax;
  explicit WideBoxInterval(const Ray& ray) : tmin(ray.tmin), tmax(ray.tmax) {}
  void reread() {}
};
inline unsigned test_boxes_in(const WideNode& node, const WideBoxRay& r, const WideBoxInterval& i, float* entry) {
  return test_boxes(node, r, i.tmin, i.tmax, entry);
}

// Bit s set when child slot s is a leaf (the reference's top bit).
inline unsigned leaf_children(const WideNode& node) {
  const __m128 lo = _mm_castsi128_ps(_mm_load_si128(reinterpret_cast<const __m128i*>(node.child)));
  const __m128 hi = _mm_castsi128_ps(_mm_load_si128(reinterpret_cast<const __m128i*>(node.child + 4)));
  return static_cast<unsigned>(_mm_movemask_ps(lo)) | (static_cast<unsigned>(_mm_movemask_ps(hi)) << 4);
}

// Pushes the children in `slots` onto the any-hit stack at `top`, highest slot first (so the lowest is
// popped first), and returns how many (the 256-bit kernels do it with one permutation).
inline std::size_t push_children(const WideNode& node, unsigned slots, std::uint32_t* top) {
  std::size_t n = 0;
  while (slots != 0) {
    const unsigned s = 31u - static_cast<unsigned>(__builtin_clz(slots));
    top[n++] = node.child[s];
    slots &= ~(1u << s);
  }
  return n;
}

#include "backends/wide/wide_traversal.inl"
#undef TWINRAY_KERNEL

}  // namespace twinray::wide_sse2
