#include "backends/bvh/bvh_binning.h"

#include "backends/simd/isa.h"

namespace twinray::bvh_binning {

namespace {

// Bins refs[b, e) into the unused grid g. kDense: clear the grid first and bin without testing `used` (for
// large ranges); kSecond: the range holds primitives of the second kind, which are counted (otherwise the
// counts stay 0). The grid is filled in place: at about 4 KiB, copying it cost more than binning a small
// range.
template <bool kDense, bool kSecond>
void bin_range(BinGrid& g, std::span<const PrimRef> refs, std::size_t b, std::size_t e, const BinMapping& map,
               std::uint32_t second_kind_begin) {
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
  __m256 box[3][kMaxBins];
  const __m256 empty = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < bins; ++k) {
      box[a][k] = empty;
      g.count[a][k] = 0;
      g.second_kind[a][k] = 0;
    }
  const __m256 negate_hi = _mm256_setr_ps(0.0f, 0.0f, 0.0f, 0.0f, -0.0f, -0.0f, -0.0f, -0.0f);
  alignas(16) std::int32_t k[4];
  for (std::size_t i = b; i < e; ++i) {
    const PrimRef& r = refs[i];
    __m128 lo, hi;
    map.bins_of(r, lo, hi, k);
    const __m256 row = _mm256_xor_ps(_mm256_load_ps(&r.lo.x), negate_hi);
    const std::uint32_t second = kSecond && r.id >= second_kind_begin ? 1u : 0u;
    for (int axis = 0; axis < 3; ++axis) {
      __m256& bin = box[axis][k[axis]];
      bin = _mm256_min_ps(row, bin);  // operand order of extend_lo / extend_hi
      ++g.count[axis][k[axis]];
      if constexpr (kSecond) g.second_kind[axis][k[axis]] += second;
    }
  }
  const __m128 sign = _mm_set1_ps(-0.0f);
  for (int a = 0; a < 3; ++a)
    for (int k2 = 0; k2 < bins; ++k2) {
      g.lo[a][k2] = _mm256_castps256_ps128(box[a][k2]);
      g.hi[a][k2] = _mm_xor_ps(_mm256_extractf128_ps(box[a][k2], 1), sign);
    }
  g.mark_used(bins);
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
  if (!second_kind_present) {
    if (dense) bin_range<true, false>(g, refs, b, e, map, second_kind_begin);
    else bin_range<false, false>(g, refs, b, e, map, second_kind_begin);
  } else {
    if (dense) bin_range<true, true>(g, refs, b, e, map, second_kind_begin);
    else bin_range<false, true>(g, refs, b, e, map, second_kind_begin);
  }
}

Split best_plane_of_cleared_grid(const BinGrid& g, int bins, const std::array<bool, 3>& usable) {
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
  // Bounds3::half_area(), (e.x e.y + e.y e.z) + e.z e.x, per lane.
  const auto half_area = [](const __m128* lo, const __m128* hi) {
    const __m128 ex = _mm_sub_ps(hi[0], lo[0]), ey = _mm_sub_ps(hi[1], lo[1]), ez = _mm_sub_ps(hi[2], lo[2]);
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(ex, ey), _mm_mul_ps(ey, ez)), _mm_mul_ps(ez, ex));
  };
  // leaf_tests(count, second) per lane: (count - second + 3) / 4 + second, exact in float.
  static_assert(kTriangleBlockLanes == 4, "blocks of four: the division is a shift");
  const auto tests = [](__m128i count, __m128i second) {
    const __m128i triangles = _mm_sub_epi32(count, second);
    return _mm_cvtepi32_ps(_mm_add_epi32(_mm_srli_epi32(_mm_add_epi32(triangles, _mm_set1_epi32(3)), 2), second));
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
    right_cost[k] = _mm_mul_ps(half_area(lo, hi), tests(count, second));
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
    const __m128 cost = _mm_add_ps(_mm_mul_ps(half_area(lo, hi), tests(count, second)), right_cost[k + 1]);
    const __m128 better = _mm_and_ps(_mm_cmplt_ps(cost, best_cost), usable_mask);
    best_cost = _mm_or_ps(_mm_and_ps(better, cost), _mm_andnot_ps(better, best_cost));
    best_plane = _mm_or_si128(_mm_and_si128(_mm_castps_si128(better), _mm_set1_epi32(k + 1)),
                              _mm_andnot_si128(_mm_castps_si128(better), best_plane));
  }
  alignas(16) float costs[4];
  alignas(16) std::int32_t planes[4];
  _mm_store_ps(costs, best_cost);
  _mm_store_si128(reinterpret_cast<__m128i*>(planes), best_plane);
  Split best;
  for (int axis = 0; axis < 3; ++axis)
    if (costs[axis] < best.cost) best = {Split::Kind::Bin, axis, planes[axis], costs[axis]};
  return best;
}

}  // namespace twinray::bvh_binning
