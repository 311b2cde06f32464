#include "backends/bvh/bvh_swept_subtree.h"

#include "backends/simd/isa.h"

#include <immintrin.h>

#include <cstddef>
#include <cstdint>
#include <limits>

namespace twinray::bvh_binning {

namespace {

// A primitive: its box as (lo, -hi), so that one min folds both ends and `lo + nhi` is minus the extent,
// whose pairwise products are the extent's (half_area_of), and its centroid. The fourth lane of `lo` holds
// the id as PrimRef::lo does (folds and areas never read it), the other fourth lanes are 0.
struct Row {
  __m128 lo, nhi, c;
};

// One swept subtree: its primitives (local index i in the order of refs[begin, end)) and per axis their
// rows in (centroid, local index) order as byte offsets (i sizeof(Row)) into `rows`, in
// two buffers: a node owns the same positions [lb, le) of the three lists, each in the buffer its bit of
// Pending::buffers names; a split leaves the split axis's list where it is (already partitioned) and
// partitions the other two stably into their other buffer.
struct Swept {
  Row rows[kSweptMax];
  std::uint16_t list[2][3][kSweptMax];
  float tests[kSweptMax + 1];  // leaf_tests(k, 0)
  BvhNode* nodes;
  PrimRef* refs;     // the range's primitives go back here in leaf order
  std::size_t base;  // refs index of list position 0
  float traversal_cost, intersection_cost;
  std::size_t max_leaf;
  float bins;
};

__attribute__((always_inline)) inline const Row& row_at(const Swept& s, std::uint16_t offset) {
  return *reinterpret_cast<const Row*>(reinterpret_cast<const char*>(s.rows) + offset);
}

// The centroid coordinate on axis a of the row at `offset`.
__attribute__((always_inline)) inline float centroid_at(const Swept& s, std::uint16_t offset, int a) {
  return *reinterpret_cast<const float*>(reinterpret_cast<const char*>(s.rows) + offset + offsetof(Row, c) + sizeof(float) * a);
}

// (e.x e.y + e.y e.z) + e.z e.x of e = lo + nhi = -(hi - lo): Bounds3::half_area()'s operations, and each
// product of two negated factors is the product of the factors.
__attribute__((always_inline)) inline float half_area_of(__m128 lo, __m128 nhi) {
  const __m128 e = _mm_add_ps(lo, nhi);
  const __m128 p = _mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1)));  // x y, y z, z x
  return _mm_cvtss_f32(_mm_add_ss(_mm_add_ss(p, _mm_shuffle_ps(p, p, _MM_SHUFFLE(3, 2, 1, 1))),
                                  _mm_shuffle_ps(p, p, _MM_SHUFFLE(3, 2, 1, 2))));
}

__attribute__((always_inline)) inline bool load(Swept& s, const PrimRef* refs, std::size_t n) {
  const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
  const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  const __m128 sign = _mm_set1_ps(-0.0f);
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  __m128 finite = _mm_castsi128_ps(_mm_set1_epi32(-1));
  for (std::size_t i = 0; i < n; ++i) {
    const __m128 raw_lo = refs[i].lo4(), hi = refs[i].hi4();
    const __m128 lo = _mm_and_ps(raw_lo, xyz);
    const __m128 centroid = _mm_and_ps(_mm_mul_ps(_mm_set1_ps(0.5f), _mm_add_ps(lo, hi)), xyz);  // as RangeInfo::add
    s.rows[i] = {raw_lo, _mm_and_ps(_mm_xor_ps(hi, sign), xyz), centroid};
    // NaN and infinities fail `|x| < inf`; the fourth lanes are not looked at.
    finite = _mm_and_ps(finite, _mm_cmplt_ps(_mm_and_ps(lo, abs_mask), inf));
    finite = _mm_and_ps(finite, _mm_cmplt_ps(_mm_and_ps(hi, abs_mask), inf));
    finite = _mm_and_ps(finite, _mm_cmplt_ps(_mm_and_ps(centroid, abs_mask), inf));
  }
  return (_mm_movemask_ps(finite) & 7) == 7;
}

// list[0][a] = the rows sorted by (centroid on axis a, local index): primitive i goes to position
// rank(i) = #{j < i : c_j <= c_i} + #{j > i : c_j < c_i} on each axis (one SSE lane per axis; every centroid
// is finite, so <= is < or ==). Exact integer counts, so any instruction set gives the same lists.
__attribute__((always_inline)) inline void sort_lists(Swept& s, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    const __m128 ci = s.rows[i].c;
    __m128i rank = _mm_setzero_si128();  // minus the counts: a true comparison is -1
    for (std::size_t j = 0; j < i; ++j) rank = _mm_add_epi32(rank, _mm_castps_si128(_mm_cmple_ps(s.rows[j].c, ci)));
    for (std::size_t j = i + 1; j < n; ++j) rank = _mm_add_epi32(rank, _mm_castps_si128(_mm_cmplt_ps(s.rows[j].c, ci)));
    alignas(16) std::int32_t r[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(r), _mm_sub_epi32(_mm_setzero_si128(), rank));
    const auto offset = static_cast<std::uint16_t>(i * sizeof(Row));
    s.list[0][0][r[0]] = offset;
    s.list[0][1][r[1]] = offset;
    s.list[0][2][r[2]] = offset;
  }
}

struct Choice {
  float cost = std::numeric_limits<float>::infinity();  // un-normalised, as Split::cost
  int axis = -1;
  std::size_t at = 0;  // list position of the right side's first primitive
};

// Sweeps every plane between two neighbours of `list` (axis a's order) over [lb, le): the cost of each side
// is its box's half area times its leaf tests, as the binned sweep computes a plane's. First minimum in
// (axis, position) order under a strict <. Every coordinate is finite here, so the operand order of the
// folds does not matter (it decides NaN and signed zeros only, and no area depends on a zero's sign).
__attribute__((always_inline)) inline void sweep_axis(const Swept& s, const std::uint16_t* list, int a, std::size_t lb,
                                                      std::size_t le, Choice& best) {
  float right_cost[kSweptMax];
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  __m128 lo = inf, nhi = inf;
  for (std::size_t j = le - 1; j > lb; --j) {  // right_cost[j]: list[j, le) on the right
    const Row& r = row_at(s, list[j]);
    lo = _mm_min_ps(lo, r.lo);
    nhi = _mm_min_ps(nhi, r.nhi);
    right_cost[j] = half_area_of(lo, nhi) * s.tests[le - j];
  }
  lo = inf;
  nhi = inf;
  for (std::size_t j = lb; j + 1 < le; ++j) {  // list[lb, j] on the left
    const Row& r = row_at(s, list[j]);
    lo = _mm_min_ps(lo, r.lo);
    nhi = _mm_min_ps(nhi, r.nhi);
    const float cost = half_area_of(lo, nhi) * s.tests[j + 1 - lb] + right_cost[j + 1];
    if (cost < best.cost) best = {cost, a, j + 1};
  }
}

// A node still to be written: list positions [lb, le), its box, which buffer each axis's list is in
// (bit a), and the node whose right child it is (UINT32_MAX: none, a left child or the root).
struct Pending {
  __m128 lo, nhi;
  std::uint8_t lb, le, buffers;
  std::uint32_t parent;
};

// Writes the node `p` to nodes[at] and decides it: a leaf (its primitives go to refs, returns false) or a
// split, whose two sides it appends to `stack`, right first (returns true).
__attribute__((always_inline)) inline bool build_node(Swept& s, const Pending& p, std::size_t at, Pending* stack, std::size_t& top) {
  const std::size_t lb = p.lb, le = p.le, m = le - lb;
  BvhNode& node = s.nodes[at];
  _mm_store_ps(&node.lo.x, p.lo);
  node.offset = static_cast<std::uint32_t>(s.base + lb);
  _mm_store_ps(&node.hi.x, _mm_xor_ps(p.nhi, _mm_set1_ps(-0.0f)));
  node.count = 0;
  const auto list_of = [&](int a) { return s.list[(p.buffers >> a) & 1][a]; };
  const auto leaf = [&] {
    node.count = static_cast<std::uint32_t>(m);
    const std::uint16_t* list = list_of(0);
    const __m128 sign = _mm_set1_ps(-0.0f);
    for (std::size_t j = lb; j < le; ++j) {  // the reference as it came: lo with the id, hi = -nhi
      const Row& r = row_at(s, list[j]);
      _mm_store_ps(&s.refs[s.base + j].lo.x, r.lo);
      _mm_store_ps(&s.refs[s.base + j].hi.x, _mm_xor_ps(r.nhi, sign));
    }
    return false;
  };
  if (m == 1) return leaf();

  // The binned builder's decision (Builder::choose_split), with the sweep in place of the binned planes.
  float extent[3];
  for (int a = 0; a < 3; ++a) {
    const std::uint16_t* list = list_of(a);
    extent[a] = centroid_at(s, list[le - 1], a) - centroid_at(s, list[lb], a);
  }
  const bool fits_leaf = m <= s.max_leaf;
  const float leaf_cost = s.intersection_cost * s.tests[m];
  int axis = -1;  // -1: leaf
  std::size_t split_at = 0;
  const auto median = [&] {  // the object median of the largest centroid extent, ties by local index
    axis = (extent[0] >= extent[1] && extent[0] >= extent[2]) ? 0 : (extent[1] >= extent[2] ? 1 : 2);
    split_at = lb + m / 2;
  };
  if (extent[0] == 0.0f && extent[1] == 0.0f && extent[2] == 0.0f) {
    median();
  } else if (fits_leaf && leaf_cost <= s.traversal_cost) {
    // A leaf whenever a binned plane exists (Builder::bin_mapping's `plane_exists`: an axis whose extent
    // is positive with a finite `bins / extent`), otherwise the median, as the binned builder decides.
    bool plane_exists = false;
    for (int a = 0; a < 3; ++a)
      plane_exists = plane_exists || (extent[a] > 0.0f && s.bins / extent[a] < std::numeric_limits<float>::infinity());
    if (!plane_exists) median();
  } else {
    Choice best;
    for (int a = 0; a < 3; ++a)
      if (extent[a] > 0.0f) sweep_axis(s, list_of(a), a, lb, le, best);
    const float area = half_area_of(p.lo, p.nhi);
    const float split_cost =
        area > 0.0f ? s.traversal_cost + s.intersection_cost * best.cost / area : std::numeric_limits<float>::infinity();
    if (!(fits_leaf && leaf_cost <= split_cost)) {
      axis = best.axis;
      split_at = best.at;
    }
  }
  if (axis < 0) return leaf();

  // The split axis's list is already partitioned, and gives both sides' boxes; the other two follow it
  // stably into their other buffer (the left side's count is known, so each entry is written once).
  const std::uint16_t* split_list = list_of(axis);
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  Pending left{inf, inf, p.lb, static_cast<std::uint8_t>(split_at), p.buffers, UINT32_MAX};
  Pending right{inf, inf, static_cast<std::uint8_t>(split_at), p.le, p.buffers, static_cast<std::uint32_t>(at)};
  std::uint8_t goes_left[kSweptMax * sizeof(Row)];  // by byte offset: only multiples of 32 are used
  for (std::size_t j = lb; j < split_at; ++j) {
    const Row& r = row_at(s, split_list[j]);
    left.lo = _mm_min_ps(left.lo, r.lo);
    left.nhi = _mm_min_ps(left.nhi, r.nhi);
    goes_left[split_list[j]] = 1;
  }
  for (std::size_t j = split_at; j < le; ++j) {
    const Row& r = row_at(s, split_list[j]);
    right.lo = _mm_min_ps(right.lo, r.lo);
    right.nhi = _mm_min_ps(right.nhi, r.nhi);
    goes_left[split_list[j]] = 0;
  }
  for (int b = 0; b < 3; ++b) {
    if (b == axis) continue;
    const int from = (p.buffers >> b) & 1;
    const std::uint16_t* src = s.list[from][b];
    std::uint16_t* dst = s.list[from ^ 1][b];
    std::size_t l = lb;  // the next left position; j - l entries went right so far, from split_at on
    for (std::size_t j = lb; j < le; ++j) {
      const std::uint16_t k = src[j];
      const std::size_t is_left = goes_left[k];
      dst[is_left != 0 ? l : split_at + j - l] = k;
      l += is_left;
    }
    left.buffers = right.buffers = static_cast<std::uint8_t>(left.buffers ^ (1u << b));
  }
  stack[top++] = right;
  stack[top++] = left;
  return true;
}

// The nodes in depth-first order from nodes[at] (a node, its left subtree, its right subtree), with an
// explicit stack so that the whole builder inlines into each instruction set's function. Returns the count.
__attribute__((always_inline)) inline std::size_t build_nodes(Swept& s, std::size_t n, std::size_t at, __m128 lo, __m128 nhi) {
  Pending stack[kSweptMax];
  std::size_t top = 0;
  stack[top++] = {lo, nhi, 0, static_cast<std::uint8_t>(n), 0, UINT32_MAX};
  std::size_t next = at;
  while (top != 0) {
    const Pending p = stack[--top];
    const std::size_t index = next++;
    if (p.parent != UINT32_MAX) s.nodes[p.parent].offset = static_cast<std::uint32_t>(index);
    build_node(s, p, index, stack, top);
  }
  return next - at;
}

__attribute__((always_inline)) inline std::size_t build_subtree(PrimRef* refs, std::size_t begin, std::size_t end, BvhNode* nodes,
                                                                std::size_t at, const BvhBuildOptions& o) {
  const std::size_t n = end - begin;
  Swept s;
  if (n < 2 || !load(s, refs + begin, n)) return 0;
  __m128 lo = s.rows[0].lo, nhi = s.rows[0].nhi;
  for (std::size_t i = 1; i < n; ++i) {
    lo = _mm_min_ps(lo, s.rows[i].lo);
    nhi = _mm_min_ps(nhi, s.rows[i].nhi);
  }
  // A box too large for finite costs takes the binned path, which guards it (Builder::choose_split).
  constexpr float kFiniteCostArea = 1e35f;
  if (!(half_area_of(lo, nhi) <= kFiniteCostArea)) return 0;
  sort_lists(s, n);
  for (std::size_t k = 0; k <= n; ++k) s.tests[k] = leaf_tests(static_cast<std::uint32_t>(k), 0);
  s.nodes = nodes;
  s.refs = refs;
  s.base = begin;
  s.traversal_cost = o.traversal_cost;
  s.intersection_cost = o.intersection_cost;
  s.max_leaf = static_cast<std::size_t>(o.max_leaf_size);
  s.bins = static_cast<float>(o.bins);
  return build_nodes(s, n, at, lo, nhi);
}

std::size_t build_subtree_sse2(PrimRef* refs, std::size_t begin, std::size_t end, BvhNode* nodes, std::size_t at,
                               const BvhBuildOptions& o) {
  return build_subtree(refs, begin, end, nodes, at, o);
}

TWINRAY_TARGET_AVX2 std::size_t build_subtree_avx2(PrimRef* refs, std::size_t begin, std::size_t end, BvhNode* nodes, std::size_t at,
                                                   const BvhBuildOptions& o) {
  return build_subtree(refs, begin, end, nodes, at, o);
}

}  // namespace

std::size_t build_swept_subtree(PrimRef* refs, std::size_t begin, std::size_t end, BvhNode* nodes, std::size_t at,
                                const BvhBuildOptions& options, bool avx2) {
  return avx2 ? build_subtree_avx2(refs, begin, end, nodes, at, options) : build_subtree_sse2(refs, begin, end, nodes, at, options);
}

}  // namespace twinray::bvh_binning
