// The 256-bit slab test of the AVX2 and AVX-512 wide kernels: each node's eight boxes in one register per
// plane. The two instruction sets run the same arithmetic and differ only in how a comparison becomes a
// bit mask (AVX2: a vector compare and movemask; AVX-512: a compare straight into a mask register), which
// the including file supplies as cmp_le_mask() and sign_mask().
//
// No include guard: wide_kernels_avx2.cpp and wide_kernels_avx512.cpp include this file once, inside their
// own namespace, after defining TWINRAY_KERNEL (the target attribute), cmp_le_mask(a, b) (bit s set when
// a[s] <= b[s], false for NaN), sign_mask(v) (bit s = the sign bit of 32-bit lane s), and how the ray's
// per-axis values are kept: the type WideSplat, make_splat(float) -> WideSplat, splat(WideSplat) -> __m256 and
// kWideSplatScalars (whether WideSplat is a scalar).
// AVX2 keeps them as broadcast vectors (its arithmetic has no broadcast memory operand); AVX-512 keeps the
// scalars, which the slab test reads as {1to8} operands of its products and broadcasts once per axis for its
// two subtractions (whose memory operand is the node's row): the same values lane by lane, without the
// set-up's nine broadcasts and nine 32-byte stores.

// The ray as the slab test needs it, set up as in wide_kernels_sse2.cpp (one division for the three
// reciprocals, the row offsets from the table of their sign bits).
struct WideBoxRay {
  // neg_inv: -(the reciprocal * kSlabNearScale); neg_inv_far: -(the reciprocal * kSlabFarScale). Negated so that
  // the slab test subtracts the plane from the origin (test_boxes_from): the node's row is then the memory
  // operand of the subtraction, with no load of its own.
  WideSplat org[3], neg_inv[3], neg_inv_far[3];
  WideOctantRows rows;

  TWINRAY_KERNEL explicit WideBoxRay(const Ray& ray) {
    const __m128 dir = _mm_setr_ps(ray.dir.x, ray.dir.y, ray.dir.z, 1.0f);
    const __m128 inv_dir = _mm_div_ps(_mm_set1_ps(1.0f), dir);
    // fl(x * -c) = -fl(x * c): rounding to nearest is symmetric, so these are the scaled reciprocals negated.
    alignas(16) float neg_inv_s[4], neg_inv_far_s[4];
    _mm_store_ps(neg_inv_s, _mm_mul_ps(inv_dir, _mm_set1_ps(-kSlabNearScale)));
    _mm_store_ps(neg_inv_far_s, _mm_mul_ps(inv_dir, _mm_set1_ps(-kSlabFarScale)));
    for (int a = 0; a < 3; ++a) {
      org[a] = make_splat(ray.org[a]);
      neg_inv[a] = make_splat(neg_inv_s[a]);
      neg_inv_far[a] = make_splat(neg_inv_far_s[a]);
    }
    rows = kWideOctantRows[static_cast<unsigned>(_mm_movemask_ps(inv_dir)) & 7u];
  }

  // Tells the compiler the values may have changed in memory (wide_traversal.inl, reread_vectors).
  TWINRAY_KERNEL void reread() {
    asm("" : "+m"(org), "+m"(neg_inv), "+m"(neg_inv_far));
  }
};

// The ray in double for the refinement (triangle_refine.h's RefineRay: (x, y, z, 0) vectors of the origin, the
// direction and its magnitude): each half of the Ray (origin and tmin, direction and tmax) converted by one
// vcvtps2pd, the fourth lane cleared by a blend. The same doubles as set_ray's three scalar conversions per
// vector (a float converts exactly, and denormals-are-zero reads a subnormal as 0 in either), in about 8
// instructions instead of 22 (GCC assembles the scalar form from conversions, unpacks and inserts).
TWINRAY_KERNEL inline void set_refine_ray(refine_detail::RefineRay& r, const Ray& ray) {
  static_assert(offsetof(Ray, tmin) == 12 && offsetof(Ray, dir) == 16, "the two halves: (org, tmin) and (dir, tmax)");
  const __m256d o = _mm256_blend_pd(_mm256_cvtps_pd(_mm_loadu_ps(&ray.org.x)), _mm256_setzero_pd(), 0b1000);
  const __m256d d = _mm256_blend_pd(_mm256_cvtps_pd(_mm_loadu_ps(&ray.dir.x)), _mm256_setzero_pd(), 0b1000);
  r.o.v = o;
  r.d.v = d;
  r.abs_d.v = _mm256_andnot_pd(_mm256_set1_pd(-0.0), d);
}

// Vertex `vert` of lane `lane` of a block as the refinement's (x, y, z, 0) doubles: the three floats gathered into
// one vector (a load and two inserts from memory) and converted by one vcvtps2pd. The same doubles as
// refine_detail::load's three scalar conversions, in 4 instructions instead of about 8 (GCC assembles the scalar
// form from conversions, an unpack, a move and an insert).
TWINRAY_KERNEL inline refine_detail::Vec4 block_vertex(const TriangleBlock& block, unsigned vert, unsigned lane) {
  __m128 p = _mm_load_ss(&block.v[vert][0][lane]);
  p = _mm_insert_ps(p, _mm_load_ss(&block.v[vert][1][lane]), 0x10);
  p = _mm_insert_ps(p, _mm_load_ss(&block.v[vert][2][lane]), 0x20);
  return {_mm256_cvtps_pd(p)};
}

// Ize's robust slab test on all eight boxes (see wide_kernels_sse2.cpp for the NaN handling, and ray_box.h
// for why the near and far distances use the reciprocal pre-scaled by kSlabNearScale and kSlabFarScale),
// with the interval given as vectors (t0: tmin, t1: tmax in every lane).
TWINRAY_KERNEL inline unsigned test_boxes_from(const WideNode& node, const WideBoxRay& r, __m256 t0, __m256 t1,
                                               float* entry) {
  const float* rows = &node.lo[0][0];
  // (org - plane) * -(scaled reciprocal) against ray_box.h's (plane - org) * (scaled reciprocal): rounding to
  // nearest is symmetric, so a non-zero difference is the same difference negated and the product is the same
  // float, its sign and a flushed zero's sign included. Two cases differ only in a sign bit: org = plane, where
  // both differences are +0 and the product is a zero of the other sign (or NaN for an infinite reciprocal, in
  // either form), and that NaN itself. Neither changes the result: max(x, t0) and min(x, t1) return their
  // second operand, the interval so far, for a NaN x and for two zeros of any signs, so t0 stays tmin or a
  // non-zero near distance (bit for bit the same entries), t1 may become a zero of the other sign only where
  // the old form gave a zero too, and t0 <= t1 compares -0 and +0 as equal: the same mask. One load fewer per
  // plane (the row is the subtraction's memory operand).
  for (int a = 0; a < 3; ++a) {
    const __m256 org = splat(r.org[a]);  // one register for both planes of the axis
    const __m256 t_near =
        _mm256_mul_ps(_mm256_sub_ps(org, _mm256_load_ps(rows + r.rows.near_row[a])), splat(r.neg_inv[a]));
    const __m256 t_far =
        _mm256_mul_ps(_mm256_sub_ps(org, _mm256_load_ps(rows + r.rows.far_row[a])), splat(r.neg_inv_far[a]));
    t0 = _mm256_max_ps(t_near, t0);
    t1 = _mm256_min_ps(t_far, t1);
  }
  _mm256_store_ps(entry, t0);
  return cmp_le_mask(t0, t1);
}
TWINRAY_KERNEL inline unsigned test_boxes(const WideNode& node, const WideBoxRay& r, float tmin, float tmax,
                                          float* entry) {
  return test_boxes_from(node, r, _mm256_set1_ps(tmin), _mm256_set1_ps(tmax), entry);
}

// The ray's own interval, which any hit keeps all along, as broadcast vectors in memory: read as memory operands
// of the slab test's max and min, where test_boxes' float arguments cost a scalar load and a broadcast each per
// node visit (the ray is behind a reference). Whole vectors on AVX-512 too: GCC broadcasts a scalar into a
// register at each visit rather than give max and min a {1to8} operand. Apart from WideBoxRay so that closest
// hit, whose tmax shrinks, does not pay for setting it up.
struct WideBoxInterval {
  __m256 tmin, tmax;
  TWINRAY_KERNEL explicit WideBoxInterval(const Ray& ray)
      : tmin(_mm256_set1_ps(ray.tmin)), tmax(_mm256_set1_ps(ray.tmax)) {}
  // As WideBoxRay::reread: read again from memory at each use, not kept in registers across the leaf tests.
  TWINRAY_KERNEL void reread() { asm("" : "+m"(tmin), "+m"(tmax)); }
};

// test_boxes against that interval: the same floats, so the same mask and entries.
TWINRAY_KERNEL inline unsigned test_boxes_in(const WideNode& node, const WideBoxRay& r, const WideBoxInterval& i,
                                             float* entry) {
  return test_boxes_from(node, r, i.tmin, i.tmax, entry);
}

// Bit s set when child slot s is a leaf (the reference's top bit).
TWINRAY_KERNEL inline unsigned leaf_children(const WideNode& node) {
  return sign_mask(_mm256_load_si256(reinterpret_cast<const __m256i*>(node.child)));
}

// Pushes the children in `slots` (a mask of the node's child slots) onto the any-hit stack at `top`, highest
// slot first, and returns how many: the node's child row permuted by kWideDescendingSlots and stored at once.
// The store writes all eight lanes; those past the pushed children fall in the stack's unused part
// (kWideStackSlack).
TWINRAY_KERNEL inline std::size_t push_children(const WideNode& node, unsigned slots, std::uint32_t* top) {
  const __m256i order =
      _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(&kWideDescendingSlots[slots])));
  const __m256i children = _mm256_load_si256(reinterpret_cast<const __m256i*>(node.child));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(top), _mm256_permutevar8x32_epi32(children, order));
  return static_cast<std::size_t>(__builtin_popcount(slots));
}
