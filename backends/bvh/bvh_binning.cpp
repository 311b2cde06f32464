#include "backends/bvh/bvh_binning.h"

#include "backends/simd/isa.h"

#include <algorithm>
#include <utility>

namespace twinray::bvh_binning {

namespace {

// Bins refs[b, e) into the unused grid g. kDense: clear the grid first and bin without testing `used` (for
// large ranges); kSecond: the range holds primitives of the second kind, which are counted (otherwise the
// counts stay 0). The grid is filled in place: at about 4 KiB, copying it cost more than binning a small
// range.
template <bool kDense, bool kSecond>
__attribute__((always_inline)) inline void bin_range(BinGrid& g, std::span<const PrimRef> refs, std::size_t b, std::size_t e,
                                                     const BinMapping& map, std::uint32_t second_kind_begin) {
  if constexpr (kDense) g.clear(map.bins);
  alignas(16) std::int32_t k[4];
  for (std::size_t i = b; i < e; ++i) {
    const PrimRef& r = refs[i];
    __m128 lo, hi;
    map.bins_of(r, lo, hi, k);
    const std::uint32_t second = kSecond && r.id >= second_kind_begin ? 1u : 0u;
    for (int axis = 0; axis < 3; ++axis) {
      if constexpr (kDense) g.extend(axis, k[axis], lo, hi, 1, second);
      else g.add(axis, k[axis], lo, hi, 1, second);
    }
  }
  if constexpr (kDense) g.mark_used(map.bins);
}

// The lazy (small-range) binning compiled for AVX2: the same operations, so the same grid; the
// three-operand forms save the register copies.
template <bool kSecond>
TWINRAY_TARGET_AVX2 void bin_small_range_avx2(BinGrid& g, std::span<const PrimRef> refs, std::size_t b, std::size_t e,
                                              const BinMapping& map, std::uint32_t second_kind_begin) {
  bin_range<false, kSecond>(g, refs, b, e, map, second_kind_begin);
}

// bin_range<true, kSecond> with AVX2: each bin's box is kept as one 8-lane row (lo, -hi), so that one min
// updates the whole box, since max(a, b) = -min(-a, -b) bit for bit: _mm_max_ps(x, acc) is
// `x > acc ? x : acc` and _mm_min_ps(-x, -acc) is `-x < -acc ? -x : -acc`, the same choice for every
// pair (signed zeros and NaN included), and negation is exact. An empty bin's row is +inf in all lanes
// (lo = +inf, hi = -inf, as BinGrid::clear). The rows are written back to the grid's SSE layout at the
// end (48 rows): the kernel takes the ranges that are binned densely (kDenseFrom).
template <bool kSecond>
TWINRAY_TARGET_AVX2 void bin_range_avx2(BinGrid& g, std::span<const PrimRef> refs, std::size_t b, std::size_t e,
                                        const BinMapping& map, std::uint32_t second_kind_begin) {
  const int bins = map.bins;
  // Bins as flat arrays of 3 x kMaxBins: axis a's bin k is entry a kMaxBins + k, so that one vector addition
  // gives the three entries a primitive updates, and one shift their byte offsets: the counts are kept at
  // the boxes' 32-byte stride (Counts), so the same offset addresses a bin's box and its counts and no
  // per-axis index arithmetic is left. Written back to the grid at the end.
  struct Counts {
    std::uint32_t count, second;
    std::uint32_t unused[6];
  };
  static_assert(sizeof(Counts) == sizeof(__m256), "one byte offset for a bin's box and counts");
  __m256 box[3 * kMaxBins];
  Counts counts[3 * kMaxBins];
  const __m256 empty = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < bins; ++k) {
      box[a * kMaxBins + k] = empty;
      counts[a * kMaxBins + k].count = 0;
      counts[a * kMaxBins + k].second = 0;
    }
  const __m256 negate_hi = _mm256_setr_ps(0.0f, 0.0f, 0.0f, 0.0f, -0.0f, -0.0f, -0.0f, -0.0f);
  const __m128i axis_base = _mm_setr_epi32(0, kMaxBins, 2 * kMaxBins, 0);
  for (std::size_t i = b; i < e; ++i) {
    const PrimRef& r = refs[i];
    const __m128i offset = _mm_slli_epi32(_mm_add_epi32(map.bins_of(r.lo4(), r.hi4()), axis_base), 5);  // x 32 bytes
    const __m256 row = _mm256_xor_ps(_mm256_load_ps(&r.lo.x), negate_hi);
    const std::uint32_t second = kSecond && r.id >= second_kind_begin ? 1u : 0u;
    const std::size_t at[3] = {static_cast<std::uint32_t>(_mm_cvtsi128_si32(offset)),
                               static_cast<std::uint32_t>(_mm_extract_epi32(offset, 1)),
                               static_cast<std::uint32_t>(_mm_extract_epi32(offset, 2))};
    for (int axis = 0; axis < 3; ++axis) {
      __m256& bin = *reinterpret_cast<__m256*>(reinterpret_cast<char*>(box) + at[axis]);
      bin = _mm256_min_ps(row, bin);  // operand order of extend_lo / extend_hi
      Counts& c = *reinterpret_cast<Counts*>(reinterpret_cast<char*>(counts) + at[axis]);
      ++c.count;
      if constexpr (kSecond) c.second += second;
    }
  }
  const __m128 sign = _mm_set1_ps(-0.0f);
  for (int a = 0; a < 3; ++a)
    for (int k2 = 0; k2 < bins; ++k2) {
      const __m256 row = box[a * kMaxBins + k2];
      g.lo[a][k2] = _mm256_castps256_ps128(row);
      g.hi[a][k2] = _mm_xor_ps(_mm256_extractf128_ps(row, 1), sign);
      g.count[a][k2] = counts[a * kMaxBins + k2].count;
      g.second_kind[a][k2] = counts[a * kMaxBins + k2].second;
    }
  g.mark_used(bins);
}

// Bounds3::half_area(), (e.x e.y + e.y e.z) + e.z e.x, per lane of boxes transposed to one row per
// coordinate (lane a: axis a's box), operation for operation as the scalar half_area() in bvh_binning.h.
__attribute__((always_inline)) inline __m128 half_area_lanes(const __m128* lo, const __m128* hi) {
  const __m128 ex = _mm_sub_ps(hi[0], lo[0]), ey = _mm_sub_ps(hi[1], lo[1]), ez = _mm_sub_ps(hi[2], lo[2]);
  return _mm_add_ps(_mm_add_ps(_mm_mul_ps(ex, ey), _mm_mul_ps(ey, ez)), _mm_mul_ps(ez, ex));
}

// leaf_tests(count, second) per lane: (count - second + 3) / 4 + second, exact in float.
__attribute__((always_inline)) inline __m128 tests_lanes(__m128i count, __m128i second) {
  static_assert(kTriangleBlockLanes == 4, "blocks of four: the division is a shift");
  const __m128i triangles = _mm_sub_epi32(count, second);
  return _mm_cvtepi32_ps(_mm_add_epi32(_mm_srli_epi32(_mm_add_epi32(triangles, _mm_set1_epi32(3)), 2), second));
}

// Three boxes (one row per axis, fourth lane unused) as one row per coordinate: lane a of out[c] is
// coordinate c of row a.
__attribute__((always_inline)) inline void transpose_rows(__m128 r0, __m128 r1, __m128 r2, __m128 (&out)[3]) {
  __m128 r3 = _mm_setzero_ps();
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  out[0] = r0;
  out[1] = r1;
  out[2] = r2;
}

// The winner of per-lane sweeps: the first minimum in (axis, plane) order, as a scalar sweep of the axes in
// turn with a strict < finds it (each lane holds its axis's first minimum).
__attribute__((always_inline)) inline Split first_best_lane(__m128 best_cost, __m128i best_plane) {
  alignas(16) float costs[4];
  alignas(16) std::int32_t planes[4];
  _mm_store_ps(costs, best_cost);
  _mm_store_si128(reinterpret_cast<__m128i*>(planes), best_plane);
  Split best;
  for (int axis = 0; axis < 3; ++axis)
    if (costs[axis] < best.cost) best = {Split::Kind::Bin, axis, planes[axis], costs[axis]};
  return best;
}

}  // namespace

void bin_range(BinGrid& g, std::span<const PrimRef> refs, std::size_t b, std::size_t e, const BinMapping& map,
               std::uint32_t second_kind_begin, bool second_kind_present, bool avx2) {
  const bool dense = e - b >= kDenseFrom;
  // Every dense range: writing the rows back costs less than the AVX2 kernel saves from 32 primitives on
  // (docs/bvh-backend.md: from 16 it cost more, from 256 it saved less).
  if (avx2 && dense) {
    if (second_kind_present) bin_range_avx2<true>(g, refs, b, e, map, second_kind_begin);
    else bin_range_avx2<false>(g, refs, b, e, map, second_kind_begin);
    return;
  }
  if (avx2) {
    if (second_kind_present) bin_small_range_avx2<true>(g, refs, b, e, map, second_kind_begin);
    else bin_small_range_avx2<false>(g, refs, b, e, map, second_kind_begin);
    return;
  }
  if (!second_kind_present) {
    if (dense) bin_range<true, false>(g, refs, b, e, map, second_kind_begin);
    else bin_range<false, false>(g, refs, b, e, map, second_kind_begin);
  } else {
    if (dense) bin_range<true, true>(g, refs, b, e, map, second_kind_begin);
    else bin_range<false, true>(g, refs, b, e, map, second_kind_begin);
  }
}

namespace {

__attribute__((always_inline)) inline std::size_t partition_in_place(PrimRef* refs, std::size_t begin, std::size_t end,
                                                                     const BinMapping& map, int axis, int plane,
                                                                     std::uint32_t second_kind_begin, RangeInfo& left,
                                                                     RangeInfo& right) {
  const __m128i planes = _mm_set1_epi32(plane);
  const auto goes_left = [&](const PrimRef& r) {
    const __m128i below = _mm_cmplt_epi32(map.bins_of(r.lo4(), r.hi4()), planes);
    return ((_mm_movemask_ps(_mm_castsi128_ps(below)) >> axis) & 1) != 0;
  };
  left = RangeInfo{};
  right = RangeInfo{};
  PrimRef* lo = refs + begin;
  PrimRef* hi = refs + end;
  for (;;) {
    while (lo < hi && goes_left(*lo)) left.add(*lo++, second_kind_begin);
    while (lo < hi && !goes_left(hi[-1])) right.add(*--hi, second_kind_begin);
    if (lo == hi) break;
    // *lo belongs right and hi[-1] left.
    std::swap(*lo, *--hi);
    left.add(*lo++, second_kind_begin);
    right.add(*hi, second_kind_begin);
  }
  return static_cast<std::size_t>(lo - refs);
}

// partition_in_place with AVX2, the sides' boxes kept in registers as one 8-lane row (lo, -hi) each, as in
// bin_range_avx2, so that one min folds a primitive into a box (max(a, b) is -min(-a, -b) bit for bit, in the
// operand order of extend_lo / extend_hi); the centroid bounds with extend_lo / extend_hi themselves (the
// centroid is one SSE row: two operations, where a (c, -c) row took three). The same classification and the
// same folds in the same order as partition_in_place, so the same primitive order and the same bits.
// kSecond: the range may hold primitives of the second kind (otherwise their count is 0 without a test).
// The mapping is copied into locals and a swap moves each reference as one 32-byte row: the stores into
// `refs` could alias `map` and forced a reload of its rows per primitive, and std::swap went through the stack.
template <bool kSecond>
TWINRAY_TARGET_AVX2 std::size_t partition_in_place_avx2(PrimRef* refs, std::size_t begin, std::size_t end, const BinMapping& mapping,
                                                        int axis, int plane, std::uint32_t second_kind_begin, RangeInfo& left,
                                                        RangeInfo& right) {
  const BinMapping map = mapping;
  const __m128i planes = _mm_set1_epi32(plane);
  const __m256 negate_hi = _mm256_setr_ps(0.0f, 0.0f, 0.0f, 0.0f, -0.0f, -0.0f, -0.0f, -0.0f);
  const __m256 empty = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  struct Side {
    __m256 box;           // (lo, -hi) of the boxes
    __m128 c_lo, c_hi;    // of the centroids, folded as RangeInfo::add (two operations, where the row took three)
    std::uint32_t second;
  };
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity()), minus_inf = _mm_set1_ps(-std::numeric_limits<float>::infinity());
  Side l{empty, inf, minus_inf, 0}, r{empty, inf, minus_inf, 0};
  const auto goes_left = [&](const PrimRef& p) {
    const __m128i below = _mm_cmplt_epi32(map.bins_of(p.lo4(), p.hi4()), planes);
    return ((_mm_movemask_ps(_mm_castsi128_ps(below)) >> axis) & 1) != 0;
  };
  const auto add = [&](Side& side, const PrimRef& p) TWINRAY_TARGET_AVX2 {
    const __m256 row = _mm256_load_ps(&p.lo.x);
    const __m128 c = _mm_mul_ps(_mm_set1_ps(0.5f), _mm_add_ps(p.lo4(), p.hi4()));  // as RangeInfo::add
    side.box = _mm256_min_ps(_mm256_xor_ps(row, negate_hi), side.box);
    side.c_lo = extend_lo(side.c_lo, c);
    side.c_hi = extend_hi(side.c_hi, c);
    if constexpr (kSecond) side.second += p.id >= second_kind_begin ? 1u : 0u;
  };
  PrimRef* lo = refs + begin;
  PrimRef* hi = refs + end;
  for (;;) {
    while (lo < hi && goes_left(*lo)) add(l, *lo++);
    while (lo < hi && !goes_left(hi[-1])) add(r, *--hi);
    if (lo == hi) break;
    // *lo belongs right and hi[-1] left.
    --hi;
    const __m256 a = _mm256_load_ps(&lo->lo.x), b = _mm256_load_ps(&hi->lo.x);
    _mm256_store_ps(&lo->lo.x, b);
    _mm256_store_ps(&hi->lo.x, a);
    add(l, *lo++);
    add(r, *hi);
  }
  const __m128 sign = _mm_set1_ps(-0.0f);
  const auto describe = [&](const Side& side, RangeInfo& info) TWINRAY_TARGET_AVX2 {
    info.lo = _mm256_castps256_ps128(side.box);
    info.hi = _mm_xor_ps(_mm256_extractf128_ps(side.box, 1), sign);
    info.c_lo = side.c_lo;
    info.c_hi = side.c_hi;
    info.second_kind = side.second;
  };
  describe(l, left);
  describe(r, right);
  return static_cast<std::size_t>(lo - refs);
}

__attribute__((always_inline)) inline void scatter(const PrimRef* from, PrimRef* to, std::size_t b, std::size_t e, std::size_t li,
                                                   std::size_t ri, const BinMapping& map, int axis, int plane,
                                                   std::uint32_t second_kind_begin, RangeInfo& left, RangeInfo& right) {
  const __m128i planes = _mm_set1_epi32(plane);
  left = RangeInfo{};
  right = RangeInfo{};
  for (std::size_t i = b; i < e; ++i) {
    const __m128i below = _mm_cmplt_epi32(map.bins_of(from[i].lo4(), from[i].hi4()), planes);
    if (((_mm_movemask_ps(_mm_castsi128_ps(below)) >> axis) & 1) != 0) {
      left.add(from[i], second_kind_begin);
      to[li++] = from[i];
    } else {
      right.add(from[i], second_kind_begin);
      to[ri++] = from[i];
    }
  }
}

// scatter() with the sides described as in partition_in_place_avx2; kSecond as there.
template <bool kSecond>
TWINRAY_TARGET_AVX2 void scatter_avx2(const PrimRef* from, PrimRef* to, std::size_t b, std::size_t e, std::size_t li, std::size_t ri,
                                      const BinMapping& map, int axis, int plane, std::uint32_t second_kind_begin, RangeInfo& left,
                                      RangeInfo& right) {
  const __m128i planes = _mm_set1_epi32(plane);
  const __m256 negate_hi = _mm256_setr_ps(0.0f, 0.0f, 0.0f, 0.0f, -0.0f, -0.0f, -0.0f, -0.0f);
  const __m256 empty = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  __m256 box[2] = {empty, empty};  // [0]: right, [1]: left; (lo, -hi)
  // The centroids' bounds folded as RangeInfo::add: two operations, where a (lo, -hi) row took three.
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity()), minus_inf = _mm_set1_ps(-std::numeric_limits<float>::infinity());
  __m128 c_lo[2] = {inf, inf}, c_hi[2] = {minus_inf, minus_inf};
  std::uint32_t second[2] = {0, 0};
  for (std::size_t i = b; i < e; ++i) {
    const PrimRef& p = from[i];
    const __m256 row = _mm256_load_ps(&p.lo.x);
    const __m128i below = _mm_cmplt_epi32(map.bins_of(p.lo4(), p.hi4()), planes);
    const int side = (_mm_movemask_ps(_mm_castsi128_ps(below)) >> axis) & 1;
    const __m128 c = _mm_mul_ps(_mm_set1_ps(0.5f), _mm_add_ps(p.lo4(), p.hi4()));  // as RangeInfo::add
    box[side] = _mm256_min_ps(_mm256_xor_ps(row, negate_hi), box[side]);
    c_lo[side] = extend_lo(c_lo[side], c);
    c_hi[side] = extend_hi(c_hi[side], c);
    if constexpr (kSecond) second[side] += p.id >= second_kind_begin ? 1u : 0u;
    _mm256_store_ps(&to[side != 0 ? li++ : ri++].lo.x, row);
  }
  const __m128 sign = _mm_set1_ps(-0.0f);
  for (int side = 0; side < 2; ++side) {
    RangeInfo& info = side != 0 ? left : right;
    info.lo = _mm256_castps256_ps128(box[side]);
    info.hi = _mm_xor_ps(_mm256_extractf128_ps(box[side], 1), sign);
    info.c_lo = c_lo[side];
    info.c_hi = c_hi[side];
    info.second_kind = second[side];
  }
}

}  // namespace

void scatter_range(const PrimRef* from, PrimRef* to, std::size_t b, std::size_t e, std::size_t left_at, std::size_t right_at,
                   const BinMapping& map, int axis, int plane, std::uint32_t second_kind_begin, bool second_kind_present,
                   RangeInfo& left, RangeInfo& right, bool avx2) {
  if (avx2 && second_kind_present) scatter_avx2<true>(from, to, b, e, left_at, right_at, map, axis, plane, second_kind_begin, left, right);
  else if (avx2) scatter_avx2<false>(from, to, b, e, left_at, right_at, map, axis, plane, second_kind_begin, left, right);
  else scatter(from, to, b, e, left_at, right_at, map, axis, plane, second_kind_begin, left, right);
}

std::size_t partition_small_range(PrimRef* refs, std::size_t begin, std::size_t end, const BinMapping& map, int axis, int plane,
                                  std::uint32_t second_kind_begin, bool second_kind_present, RangeInfo& left, RangeInfo& right,
                                  bool avx2) {
  if (avx2) {
    if (second_kind_present) return partition_in_place_avx2<true>(refs, begin, end, map, axis, plane, second_kind_begin, left, right);
    return partition_in_place_avx2<false>(refs, begin, end, map, axis, plane, second_kind_begin, left, right);
  }
  return partition_in_place(refs, begin, end, map, axis, plane, second_kind_begin, left, right);
}

namespace {

__attribute__((always_inline)) inline Split sweep_cleared_grid(const BinGrid& g, int bins, const std::array<bool, 3>& usable) {
  struct Soa {
    __m128 lo[3], hi[3];  // per coordinate, one lane per axis
  };
  Soa soa[kMaxBins];
  __m128 right_cost[kMaxBins];
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity()), minus_inf = _mm_set1_ps(-std::numeric_limits<float>::infinity());
  for (int k = 0; k < bins; ++k) {
    __m128 l0 = g.lo[0][k], l1 = g.lo[1][k], l2 = g.lo[2][k], l3 = _mm_setzero_ps();
    __m128 h0 = g.hi[0][k], h1 = g.hi[1][k], h2 = g.hi[2][k], h3 = _mm_setzero_ps();
    _MM_TRANSPOSE4_PS(l0, l1, l2, l3);
    _MM_TRANSPOSE4_PS(h0, h1, h2, h3);
    soa[k] = {{l0, l1, l2}, {h0, h1, h2}};
  }
  const auto counts = [&](const std::uint32_t (&c)[3][kMaxBins], int k) {
    return _mm_setr_epi32(static_cast<int>(c[0][k]), static_cast<int>(c[1][k]), static_cast<int>(c[2][k]), 0);
  };

  __m128 lo[3] = {inf, inf, inf}, hi[3] = {minus_inf, minus_inf, minus_inf};
  __m128i count = _mm_setzero_si128(), second = _mm_setzero_si128();
  for (int k = bins - 1; k > 0; --k) {  // right_cost[k]: bins k.. on the right
    for (int c = 0; c < 3; ++c) {
      lo[c] = extend_lo(lo[c], soa[k].lo[c]);
      hi[c] = extend_hi(hi[c], soa[k].hi[c]);
    }
    count = _mm_add_epi32(count, counts(g.count, k));
    second = _mm_add_epi32(second, counts(g.second_kind, k));
    right_cost[k] = _mm_mul_ps(half_area_lanes(lo, hi), tests_lanes(count, second));
  }

  const __m128 usable_mask = _mm_castsi128_ps(_mm_setr_epi32(usable[0] ? -1 : 0, usable[1] ? -1 : 0, usable[2] ? -1 : 0, 0));
  __m128 best_cost = inf;
  __m128i best_plane = _mm_setzero_si128();
  for (int c = 0; c < 3; ++c) {
    lo[c] = inf;
    hi[c] = minus_inf;
  }
  count = _mm_setzero_si128();
  second = _mm_setzero_si128();
  for (int k = 0; k + 1 < bins; ++k) {  // plane k + 1: bins ..k on the left
    for (int c = 0; c < 3; ++c) {
      lo[c] = extend_lo(lo[c], soa[k].lo[c]);
      hi[c] = extend_hi(hi[c], soa[k].hi[c]);
    }
    count = _mm_add_epi32(count, counts(g.count, k));
    second = _mm_add_epi32(second, counts(g.second_kind, k));
    const __m128 cost = _mm_add_ps(_mm_mul_ps(half_area_lanes(lo, hi), tests_lanes(count, second)), right_cost[k + 1]);
    const __m128 better = _mm_and_ps(_mm_cmplt_ps(cost, best_cost), usable_mask);
    best_cost = _mm_or_ps(_mm_and_ps(better, cost), _mm_andnot_ps(better, best_cost));
    best_plane = _mm_or_si128(_mm_and_si128(_mm_castps_si128(better), _mm_set1_epi32(k + 1)),
                              _mm_andnot_si128(_mm_castps_si128(better), best_plane));
  }
  return first_best_lane(best_cost, best_plane);
}

TWINRAY_TARGET_AVX2 Split sweep_cleared_grid_avx2(const BinGrid& g, int bins, const std::array<bool, 3>& usable) {
  return sweep_cleared_grid(g, bins, usable);
}

}  // namespace

Split best_plane_of_cleared_grid(const BinGrid& g, int bins, const std::array<bool, 3>& usable, bool avx2) {
  return avx2 ? sweep_cleared_grid_avx2(g, bins, usable) : sweep_cleared_grid(g, bins, usable);
}

namespace {

// best_plane_of_occupied_bins; kSecond: the grid counts primitives of the second kind. Inlined into an SSE2
// and an AVX2 function (the same operations, so the same bits; AVX2's three-operand forms save the register
// copies of this register-bound loop).
template <bool kSecond>
__attribute__((always_inline)) inline Split sweep_occupied_bins(const BinGrid& g, const std::array<bool, 3>& usable) {
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  // occupied[i][a]: axis a's i-th occupied bin, or 0 past its last (never a winner's plane, see `open`);
  // steps: the most occupied bins of a usable axis.
  alignas(16) std::int32_t occupied[kMaxBins][4];
  std::uint32_t bits[3];
  int m[3];
  int steps = 0;
  for (int a = 0; a < 3; ++a) {
    bits[a] = usable[static_cast<std::size_t>(a)] ? g.used[a] : 0u;
    m[a] = __builtin_popcount(bits[a]);
    steps = std::max(steps, m[a]);
  }
  if (steps < 2) return {};  // no axis has a plane with both sides occupied
  for (int i = 0; i < steps; ++i) {
    for (int a = 0; a < 3; ++a) {
      occupied[i][a] = bits[a] != 0 ? __builtin_ctz(bits[a]) : 0;
      bits[a] &= bits[a] - 1;
    }
    occupied[i][3] = 0;
  }

  // Step i, transposed: lane a holds axis a's i-th occupied bin, or an empty bin (a box that leaves any box
  // it extends as it is: min(+inf, x) is x for every x, NaN included, and likewise max; no primitives)
  // past the axis's last. Gathered during the right sweep, which walks the steps backwards, and kept for
  // the left sweep.
  struct Step {
    __m128 lo[3], hi[3];
    __m128i count, second;
  };
  Step step[kMaxBins];
  alignas(16) static constexpr float kEmptyLo[4] = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                                                    std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity()};
  alignas(16) static constexpr float kEmptyHi[4] = {-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                                                    -std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()};
  static constexpr std::uint32_t kNone = 0;
  const auto gather = [&](int i) {
    Step& st = step[i];
    __m128 lo[3], hi[3];
    std::uint32_t count[3], second[3];
    for (int a = 0; a < 3; ++a) {
      const bool real = i < m[a];
      const int k = occupied[i][a];
      lo[a] = _mm_load_ps(real ? reinterpret_cast<const float*>(&g.lo[a][k]) : kEmptyLo);
      hi[a] = _mm_load_ps(real ? reinterpret_cast<const float*>(&g.hi[a][k]) : kEmptyHi);
      count[a] = *(real ? &g.count[a][k] : &kNone);
      if constexpr (kSecond) second[a] = *(real ? &g.second_kind[a][k] : &kNone);
    }
    transpose_rows(lo[0], lo[1], lo[2], st.lo);
    transpose_rows(hi[0], hi[1], hi[2], st.hi);
    st.count = _mm_setr_epi32(static_cast<int>(count[0]), static_cast<int>(count[1]), static_cast<int>(count[2]), 0);
    if constexpr (kSecond)
      st.second = _mm_setr_epi32(static_cast<int>(second[0]), static_cast<int>(second[1]), static_cast<int>(second[2]), 0);
    else
      st.second = _mm_setzero_si128();
  };

  // right_cost[i]: axis a's occupied bins i.. on the right (lane a, for i < m[a]). The scalar sweep starts
  // from the last occupied bin's box and extends it by that bin again, which leaves it as it is; so does
  // starting from an empty box here, except for a NaN coordinate, hence the last bins' own boxes.
  __m128 right_cost[kMaxBins];
  __m128 lo[3], hi[3];
  {
    __m128 last_lo[3], last_hi[3];
    for (int a = 0; a < 3; ++a) {  // every lane of an axis with a plane has m[a] >= 2
      const bool real = m[a] > 0;
      const int k = occupied[real ? m[a] - 1 : 0][a];
      last_lo[a] = _mm_load_ps(real ? reinterpret_cast<const float*>(&g.lo[a][k]) : kEmptyLo);
      last_hi[a] = _mm_load_ps(real ? reinterpret_cast<const float*>(&g.hi[a][k]) : kEmptyHi);
    }
    transpose_rows(last_lo[0], last_lo[1], last_lo[2], lo);
    transpose_rows(last_hi[0], last_hi[1], last_hi[2], hi);
  }
  __m128i count = _mm_setzero_si128(), second = _mm_setzero_si128();
  for (int i = steps - 1; i > 0; --i) {
    gather(i);
    for (int c = 0; c < 3; ++c) {
      lo[c] = extend_lo(lo[c], step[i].lo[c]);
      hi[c] = extend_hi(hi[c], step[i].hi[c]);
    }
    count = _mm_add_epi32(count, step[i].count);
    if constexpr (kSecond) second = _mm_add_epi32(second, step[i].second);
    right_cost[i] = _mm_mul_ps(half_area_lanes(lo, hi), tests_lanes(count, second));
  }
  gather(0);

  // The plane after axis a's i-th occupied bin exists while i + 1 < m[a].
  const __m128i planes_of_axis = _mm_setr_epi32(m[0], m[1], m[2], 0);
  __m128 best_cost = inf;
  __m128i best_plane = _mm_setzero_si128();
  for (int c = 0; c < 3; ++c) {
    lo[c] = step[0].lo[c];
    hi[c] = step[0].hi[c];
  }
  count = _mm_setzero_si128();
  second = _mm_setzero_si128();
  for (int i = 0; i + 1 < steps; ++i) {
    for (int c = 0; c < 3; ++c) {
      lo[c] = extend_lo(lo[c], step[i].lo[c]);
      hi[c] = extend_hi(hi[c], step[i].hi[c]);
    }
    count = _mm_add_epi32(count, step[i].count);
    if constexpr (kSecond) second = _mm_add_epi32(second, step[i].second);
    const __m128 cost = _mm_add_ps(_mm_mul_ps(half_area_lanes(lo, hi), tests_lanes(count, second)), right_cost[i + 1]);
    const __m128 open = _mm_castsi128_ps(_mm_cmpgt_epi32(planes_of_axis, _mm_set1_epi32(i + 1)));
    const __m128 better = _mm_and_ps(_mm_cmplt_ps(cost, best_cost), open);
    const __m128i plane = _mm_add_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(occupied[i])), _mm_set1_epi32(1));
    best_cost = _mm_or_ps(_mm_and_ps(better, cost), _mm_andnot_ps(better, best_cost));
    best_plane = _mm_or_si128(_mm_and_si128(_mm_castps_si128(better), plane), _mm_andnot_si128(_mm_castps_si128(better), best_plane));
  }
  return first_best_lane(best_cost, best_plane);
}

template <bool kSecond>
Split sweep_occupied_bins_sse2(const BinGrid& g, const std::array<bool, 3>& usable) {
  return sweep_occupied_bins<kSecond>(g, usable);
}

template <bool kSecond>
TWINRAY_TARGET_AVX2 Split sweep_occupied_bins_avx2(const BinGrid& g, const std::array<bool, 3>& usable) {
  return sweep_occupied_bins<kSecond>(g, usable);
}

}  // namespace

Split best_plane_of_occupied_bins(const BinGrid& g, const std::array<bool, 3>& usable, bool second_kind_present, bool avx2) {
  if (avx2) return second_kind_present ? sweep_occupied_bins_avx2<true>(g, usable) : sweep_occupied_bins_avx2<false>(g, usable);
  return second_kind_present ? sweep_occupied_bins_sse2<true>(g, usable) : sweep_occupied_bins_sse2<false>(g, usable);
}

}  // namespace twinray::bvh_binning
