#include "backends/bvh/bvh_builder.h"

#include "backends/bvh/primitive_store.h"
#include "backends/simd/isa.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace twinray {

void validate(const BvhBuildOptions& o) {
  if (o.bins < 12 || o.bins > 32) throw std::invalid_argument("bvh: bins must be in 12..32, got " + std::to_string(o.bins));
  if (o.max_leaf_size < 1 || o.max_leaf_size > 255)
    throw std::invalid_argument("bvh: max_leaf_size must be in 1..255, got " + std::to_string(o.max_leaf_size));
  if (!(o.traversal_cost > 0.0f) || !(o.intersection_cost > 0.0f) || !std::isfinite(o.traversal_cost) ||
      !std::isfinite(o.intersection_cost))
    throw std::invalid_argument("bvh: traversal_cost and intersection_cost must be positive and finite");
}

namespace {

constexpr int kMaxBins = 32;
// From this depth on only object-median splits are made. Each halves the primitive count, so at most 32
// more levels (2^32 primitives) plus one split by kind follow: the tree stays within kBvhMaxDepth.
constexpr std::size_t kMedianOnlyDepth = kBvhMaxDepth - 1 - 33;
// Subtrees with fewer primitives are built on the calling thread: task overhead would dominate.
constexpr std::size_t kParallelGrain = 4096;
// Nodes with at least this many primitives bin and partition in parallel chunks of kRangeChunk (the
// top few levels, where the recursion alone has fewer subtrees than threads).
constexpr std::size_t kParallelRangeGrain = std::size_t{1} << 15;
constexpr std::size_t kRangeChunk = std::size_t{1} << 13;

// A primitive as the builder moves it: 32 bytes, two SSE loads (lo with the id in its fourth lane, hi with
// padding). The centroid is recomputed where needed, exactly as Bounds3::center() computes it.
struct alignas(32) PrimRef {  // 32: one aligned AVX load
  glm::vec3 lo;
  std::uint32_t id;
  glm::vec3 hi;
  float pad;  // no initialiser: PrimRef stays trivially constructible, so scratch arrays are not cleared

  Bounds3 box() const { return Bounds3{lo, hi}; }
  glm::vec3 centroid() const { return 0.5f * (lo + hi); }
  __m128 lo4() const { return _mm_load_ps(&lo.x); }  // fourth lane: the id's bits, never used as a float
  __m128 hi4() const { return _mm_load_ps(&hi.x); }
};
static_assert(sizeof(PrimRef) == 32 && offsetof(PrimRef, hi) == 16, "two 16-byte rows");

// SSE min and max with glm's semantics, operand for operand: glm::min(acc, x) is `x < acc ? x : acc`,
// which is _mm_min_ps(x, acc) (and likewise max), so boxes folded here are bit-identical to Bounds3::extend
// (signed zeros included) and the tree does not depend on which of the two computed them.
inline __m128 extend_lo(__m128 acc, __m128 x) { return _mm_min_ps(x, acc); }
inline __m128 extend_hi(__m128 acc, __m128 x) { return _mm_max_ps(x, acc); }

inline glm::vec3 xyz(__m128 v) {
  alignas(16) float f[4];
  _mm_store_ps(f, v);
  return {f[0], f[1], f[2]};
}

// Bounds3::half_area() of a box that holds at least one primitive, operation for operation:
// (e.x e.y + e.y e.z) + e.z e.x.
inline float half_area(__m128 lo, __m128 hi) {
  const __m128 e = _mm_sub_ps(hi, lo);
  const __m128 p = _mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1)));  // x y, y z, z x
  return _mm_cvtss_f32(_mm_add_ss(_mm_add_ss(p, _mm_shuffle_ps(p, p, _MM_SHUFFLE(3, 2, 1, 1))),
                                  _mm_shuffle_ps(p, p, _MM_SHUFFLE(3, 2, 1, 2))));
}

// Primitive tests a leaf of `count` primitives costs, `second_kind` of them spheres: triangles are tested
// four at a time (triangle_block.h), so a leaf of 1..4 triangles costs one test, 5..8 two; spheres one
// each. Counting blocks rather than triangles is what lets the SAH stop at full blocks instead of
// splitting them (Embree's builders count SIMD blocks the same way).
inline float leaf_tests(std::uint32_t count, std::uint32_t second_kind) {
  const std::uint32_t triangles = count - second_kind;
  return static_cast<float>((triangles + kTriangleBlockLanes - 1) / kTriangleBlockLanes + second_kind);
}

struct Split {
  enum class Kind { None, Bin, ObjectMedian, ByKind } kind = Kind::None;
  int axis = 0;
  int bin = 0;            // Bin: primitives in bins [0, bin) go left
  float cost = INFINITY;  // Bin: SAH cost relative to the node's area, in builder units
};

// What a node's split decision needs to know about its primitives, gathered by its parent while it
// partitions (one pass over the primitives per level instead of two).
// SSE rows, folded like Bounds3::extend (bit-identical, see extend_lo).
struct RangeInfo {
  __m128 lo = _mm_set1_ps(std::numeric_limits<float>::infinity()), hi = _mm_set1_ps(-std::numeric_limits<float>::infinity());
  __m128 c_lo = lo, c_hi = hi;    // centroid bounds
  std::uint32_t second_kind = 0;  // how many are of the second kind

  void add(const PrimRef& r, std::uint32_t second_kind_begin) {
    const __m128 p_lo = r.lo4(), p_hi = r.hi4();
    const __m128 c = _mm_mul_ps(_mm_set1_ps(0.5f), _mm_add_ps(p_lo, p_hi));
    lo = extend_lo(lo, p_lo);
    hi = extend_hi(hi, p_hi);
    c_lo = extend_lo(c_lo, c);
    c_hi = extend_hi(c_hi, c);
    second_kind += r.id >= second_kind_begin ? 1u : 0u;
  }
  void merge(const RangeInfo& o) {
    lo = extend_lo(lo, o.lo);
    hi = extend_hi(hi, o.hi);
    c_lo = extend_lo(c_lo, o.c_lo);
    c_hi = extend_hi(c_hi, o.c_hi);
    second_kind += o.second_kind;
  }
  Bounds3 box() const { return {xyz(lo), xyz(hi)}; }
  Bounds3 centroids() const { return {xyz(c_lo), xyz(c_hi)}; }
};

// The bins of all three axes, filled in one pass over the primitives: per axis and bin the box (SSE rows,
// fourth lane unused), the primitive count and how many of them are of the second kind. Binning was two
// thirds of a build's instructions, so one primitive is binned on all three axes with a handful of SSE
// operations instead of six scalar min/max per axis (docs/bvh-backend.md has the measurements).
struct BinGrid {
  // Bit k of used[axis]: bin k holds a primitive. Unused bins are never read, so a small range's grid needs
  // no initialisation: most nodes are small (a few primitives in 3 x 16 bins), and clearing and sweeping
  // all bins cost more than binning their primitives. Large ranges clear the grid instead and bin without
  // a branch (see bin_range).
  std::uint32_t used[3] = {0, 0, 0};
  __m128 lo[3][kMaxBins], hi[3][kMaxBins];
  std::uint32_t count[3][kMaxBins], second_kind[3][kMaxBins];

  // Adds a box to a bin. A bin's first box is stored as it is, which is what extending the empty box gives.
  void add(int a, int k, __m128 box_lo, __m128 box_hi, std::uint32_t n, std::uint32_t second) {
    const std::uint32_t bit = 1u << k;
    if ((used[a] & bit) == 0) {
      used[a] |= bit;
      lo[a][k] = box_lo;
      hi[a][k] = box_hi;
      count[a][k] = n;
      second_kind[a][k] = second;
    } else {
      extend(a, k, box_lo, box_hi, n, second);
    }
  }
  void extend(int a, int k, __m128 box_lo, __m128 box_hi, std::uint32_t n, std::uint32_t second) {
    lo[a][k] = extend_lo(lo[a][k], box_lo);
    hi[a][k] = extend_hi(hi[a][k], box_hi);
    count[a][k] += n;
    second_kind[a][k] += second;
  }

  // Every bin of [0, bins) empty, for extend(); mark_used() afterwards.
  void clear(int bins) {
    const __m128 pos = _mm_set1_ps(std::numeric_limits<float>::infinity()), neg = _mm_set1_ps(-std::numeric_limits<float>::infinity());
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < bins; ++k) {
        lo[a][k] = pos;
        hi[a][k] = neg;
        count[a][k] = 0;
        second_kind[a][k] = 0;
      }
  }
  void mark_used(int bins) {
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < bins; ++k) used[a] |= count[a][k] != 0 ? 1u << k : 0u;
  }

  void merge(const BinGrid& o) {
    for (int a = 0; a < 3; ++a)
      for (std::uint32_t m = o.used[a]; m != 0; m &= m - 1) {
        const int k = __builtin_ctz(m);
        add(a, k, o.lo[a][k], o.hi[a][k], o.count[a][k], o.second_kind[a][k]);
      }
  }
};

// How a range of primitives maps to bins: a centroid coordinate c falls in bin (c - lo) * scale truncated,
// clamped to [0, bins - 1] (c == hi maps to `bins`, and rounding may overshoot). The clamp comes before the
// truncation, which gives the same index as after it for every finite value (a NaN, from an unusable axis,
// becomes bin 0: max_ps returns its second operand). Binning and partitioning both use this one mapping.
struct BinMapping {
  __m128 c_lo, c_scale, top;
  int bins;

  // The bins of a box's centroid on the three axes (fourth lane unused).
  __m128i bins_of(__m128 lo, __m128 hi) const {
    const __m128 c = _mm_mul_ps(_mm_set1_ps(0.5f), _mm_add_ps(lo, hi));
    const __m128 x = _mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(c, c_lo), c_scale), _mm_setzero_ps()), top);
    return _mm_cvttps_epi32(x);
  }
  void bins_of(const PrimRef& r, __m128& lo, __m128& hi, std::int32_t* k) const {
    lo = r.lo4();
    hi = r.hi4();
    _mm_store_si128(reinterpret_cast<__m128i*>(k), bins_of(lo, hi));
  }
};

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

// Clearing 3 x 16 bins costs about as much as the branches of binning 32 primitives lazily; from the same
// size on, sweeping the cleared grid's three axes at once beats sweeping the occupied bins one axis at a
// time (from 16 or 24 it cost more instructions, docs/bvh-backend.md).
constexpr std::size_t kDenseFrom = 32;

inline void bin_range(BinGrid& g, std::span<const PrimRef> refs, std::size_t b, std::size_t e, const BinMapping& map,
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

// The best plane of a cleared grid (every bin initialised, see BinGrid::clear) on the usable axes. The
// three axes are swept at once, one SSE lane each: a bin's three boxes are transposed so that a vector
// holds one coordinate of the three axes' bins. The costs are computed lane for lane with the operations,
// in the order, of the scalar sweep below (half_area, leaf_tests), so they are bit-identical to it, and
// the winner is the first minimum in (axis, plane) order, as the scalar sweep's strict < finds it. Every
// plane is a candidate: a plane after an empty bin has the sides, hence the cost, of the plane before it
// and loses the tie; a plane with an empty side costs inf * 0 = NaN, which never compares less. Worth it
// for large ranges, whose bins are mostly occupied; small ranges sweep their few occupied bins instead.
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

class Builder {
 public:
  // `nodes` has room for 2 refs.size() - 1 nodes (build() writes them).
  Builder(std::span<PrimRef> refs, BvhNode* nodes, std::uint32_t second_kind_begin, const BvhBuildOptions& o, Isa isa)
      : home_(refs.data()), nodes_(nodes), second_kind_begin_(second_kind_begin), o_(o), avx2_(isa >= Isa::Avx2) {
    if (refs.size() >= kParallelRangeGrain) {
      // Uninitialised: a range is scattered into it before it is read.
      static_assert(std::is_trivially_default_constructible_v<PrimRef>, "new[] must not initialise the scratch");
      scratch_owner_.reset(new PrimRef[refs.size()]);
      scratch_ = scratch_owner_.get();
    }
  }

  // Box, centroid bounds and kind count of refs[begin, end): in parallel for a large range.
  RangeInfo info_of(const PrimRef* refs, std::size_t begin, std::size_t end) const {
    return reduce_chunks<RangeInfo>(begin, end, [&](std::size_t b, std::size_t e) {
      RangeInfo info;
      for (std::size_t i = b; i < e; ++i) info.add(refs[i], second_kind_begin_);
      return info;
    }, [](RangeInfo& acc, const RangeInfo& part) { acc.merge(part); });
  }

  // Writes the whole tree to nodes_ (room for 2 n - 1 nodes, see build()) and returns its node count.
  // In two phases when the input is large: first the large nodes (kParallelRangeGrain primitives or more),
  // whose binning and partitions run in parallel chunks and move the primitives between two arrays; then,
  // the scratch array freed, the small subtrees below them, in parallel. The tree is the same as one
  // depth-first build gives (node positions depend on primitive counts only; compact() orders them).
  std::size_t build_tree(std::size_t n, const RangeInfo& root) {
    if (n < kParallelRangeGrain) return build(0, n, root, 0, 0);
    std::vector<Pending> below;
    std::size_t count = build_large(0, n, root, 0, 0, false, below);
    scratch_owner_.reset();  // only large ranges were ever in it
    std::vector<std::size_t> counts(below.size());
    const auto run = [&](std::size_t k) { counts[k] = build(below[k].begin, below[k].end, below[k].info, below[k].depth, below[k].at); };
    if (o_.parallel) tbb::parallel_for(std::size_t{0}, below.size(), std::size_t{1}, run);
    else for (std::size_t k = 0; k < below.size(); ++k) run(k);
    for (const std::size_t c : counts) count += c;
    return count;
  }

  // Copies the subtree at nodes_[at] to `out` depth-first without the gaps the parallel build left, with
  // its child offsets rebased, and counts its leaves and depth on the way.
  void compact(std::size_t at, std::size_t depth, BvhTree& out) const {
    out.max_depth = std::max(out.max_depth, depth);
    const BvhNode& node = nodes_[at];
    const std::size_t index = out.nodes.size();
    out.nodes.push_back(node);
    if (node.is_leaf()) {
      ++out.leaves;
      return;
    }
    compact(at + 1, depth + 1, out);
    out.nodes[index].offset = static_cast<std::uint32_t>(out.nodes.size());
    compact(node.second_child(), depth + 1, out);
  }

 private:
  // A subtree under the large nodes, built in the second phase of build_tree().
  struct Pending {
    std::size_t begin, end;
    RangeInfo info;
    std::size_t depth, at;
  };

  // A large node (kParallelRangeGrain primitives or more, always split: never a leaf) at nodes_[at] and
  // the large nodes below it; the small subtrees below them are appended to `below`. Its primitives are
  // in the scratch array if `in_scratch`. Each child gets the room of its worst case (see build()), so
  // where the small subtrees go is known before they are built. Returns the number of large nodes written.
  std::size_t build_large(std::size_t begin, std::size_t end, const RangeInfo& info, std::size_t depth, std::size_t at,
                          bool in_scratch, std::vector<Pending>& below) const {
    const std::size_t n = end - begin;
    PrimRef* const refs = in_scratch ? scratch_ : home_;
    const Bounds3 box = info.box(), centroids = info.centroids();
    const bool mixed = info.second_kind != 0 && info.second_kind != n;
    const Split split = choose_split(refs, begin, end, box, centroids, depth, mixed, info.second_kind);
    RangeInfo left_info, right_info;
    bool children_in_scratch = in_scratch;
    const std::size_t mid = partition(refs, begin, end, centroids, split, left_info, right_info, children_in_scratch);
    const std::size_t right_at = at + 2 * (mid - begin);  // after the left child's 2 (mid - begin) - 1
    nodes_[at] = BvhNode{box.lo, static_cast<std::uint32_t>(right_at), box.hi, 0};
    std::size_t count = 1;
    const auto child = [&](std::size_t b, std::size_t e, const RangeInfo& child_info, std::size_t child_at) {
      if (e - b >= kParallelRangeGrain) {
        count += build_large(b, e, child_info, depth + 1, child_at, children_in_scratch, below);
        return;
      }
      // Small ranges are partitioned in place in the home array.
      if (children_in_scratch)
        for_chunks(b, e, [&](std::size_t cb, std::size_t ce) { std::copy(scratch_ + cb, scratch_ + ce, home_ + cb); });
      below.push_back({b, e, child_info, depth + 1, child_at});
    };
    child(begin, mid, left_info, at + 1);
    child(mid, end, right_info, right_at);
    return count;
  }

  // Writes the subtree over the small range [begin, end) of the home array, described by `info`, to
  // nodes_[at, at + 2 n - 1) in depth-first order and returns how many nodes it wrote; child offsets are
  // indices into nodes_. A serial subtree is contiguous from `at`. A parallel node gives each child the room
  // its worst case needs (a subtree over m primitives has at most 2 m - 1 nodes, since every leaf holds at
  // least one), so both children are built in place at once and nothing is copied; the gaps this leaves are
  // squeezed out by one depth-first copy at the end (compact()).
  std::size_t build(std::size_t begin, std::size_t end, const RangeInfo& info, std::size_t depth, std::size_t at) const {
    const std::size_t n = end - begin;
    const bool mixed = info.second_kind != 0 && info.second_kind != n;

    const Bounds3 box = info.box(), centroids = info.centroids();
    BvhNode& node = nodes_[at];
    node = BvhNode{box.lo, static_cast<std::uint32_t>(begin), box.hi, 0};

    const Split split = choose_split(home_, begin, end, box, centroids, depth, mixed, info.second_kind);
    if (split.kind == Split::Kind::None) {
      node.count = static_cast<std::uint32_t>(n) | (info.second_kind == n ? BvhNode::kSphereLeafBit : 0u);
      return 1;
    }
    RangeInfo left_info, right_info;
    bool in_scratch = false;  // small ranges stay in place
    const std::size_t mid = partition(home_, begin, end, centroids, split, left_info, right_info, in_scratch);

    if (o_.parallel && n >= kParallelGrain) {
      const std::size_t right_at = at + 2 * (mid - begin);  // after the left child's 2 (mid - begin) - 1
      std::size_t left_nodes = 0, right_nodes = 0;
      tbb::parallel_invoke([&] { left_nodes = build(begin, mid, left_info, depth + 1, at + 1); },
                           [&] { right_nodes = build(mid, end, right_info, depth + 1, right_at); });
      node.offset = static_cast<std::uint32_t>(right_at);
      return 1 + left_nodes + right_nodes;
    }
    const std::size_t left_nodes = build(begin, mid, left_info, depth + 1, at + 1);
    node.offset = static_cast<std::uint32_t>(at + 1 + left_nodes);
    return 1 + left_nodes + build(mid, end, right_info, depth + 1, at + 1 + left_nodes);
  }

  // Runs `body(b, e)` over fixed chunks of [begin, end) and folds the results in chunk order. The chunks
  // do not depend on the thread count, and every fold used here (min, max, integer sums) is exact, so the
  // result is the same serial or parallel. Large ranges run in TBB tasks when the build is parallel: the
  // top levels of the tree are where a parallel recursion alone leaves threads idle.
  template <class T, class Body, class Fold>
  T reduce_chunks(std::size_t begin, std::size_t end, const Body& body, const Fold& fold) const {
    const std::size_t n = end - begin;
    if (!o_.parallel || n < kParallelRangeGrain) return body(begin, end);
    const std::size_t chunks = (n + kRangeChunk - 1) / kRangeChunk;
    std::vector<T> parts(chunks);
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
      parts[c] = body(begin + c * kRangeChunk, std::min(end, begin + (c + 1) * kRangeChunk));
    });
    T acc = parts[0];
    for (std::size_t c = 1; c < chunks; ++c) fold(acc, parts[c]);
    return acc;
  }

  // Runs `body(b, e)` over the fixed chunks of [begin, end), in parallel when the build is.
  template <class Body>
  void for_chunks(std::size_t begin, std::size_t end, const Body& body) const {
    const std::size_t chunks = (end - begin + kRangeChunk - 1) / kRangeChunk;
    const auto run = [&](std::size_t c) { body(begin + c * kRangeChunk, std::min(end, begin + (c + 1) * kRangeChunk)); };
    if (o_.parallel) tbb::parallel_for(std::size_t{0}, chunks, run);
    else for (std::size_t c = 0; c < chunks; ++c) run(c);
  }

  Split choose_split(const PrimRef* refs, std::size_t begin, std::size_t end, const Bounds3& box, const Bounds3& centroids,
                     std::size_t depth, bool mixed, std::uint32_t second_kind) const {
    const std::size_t n = end - begin;
    const bool fits_leaf = n <= static_cast<std::size_t>(o_.max_leaf_size);
    if (n == 1 || (fits_leaf && !mixed && (o_.split_method == BvhSplitMethod::ObjectMedian || depth >= kMedianOnlyDepth)))
      return {};
    if (fits_leaf && mixed) return {Split::Kind::ByKind};

    const bool centroids_coincide = centroids.extent() == glm::vec3(0.0f);
    if (o_.split_method == BvhSplitMethod::ObjectMedian || depth >= kMedianOnlyDepth || centroids_coincide)
      return {Split::Kind::ObjectMedian, centroids.largest_axis()};

    const float area = box.half_area();
    const float leaf_cost = o_.intersection_cost * leaf_tests(static_cast<std::uint32_t>(n), second_kind);
    // A node that may be a leaf and whose leaf costs no more than one interior step stays a leaf whenever a
    // binned split exists: the split's cost below is C_trav plus a non-negative term, never less than the
    // leaf's. Which split is best does not matter then, only whether there is one, so the sweep is skipped.
    // These are the most common calls (every leaf of 2 or more primitives is one: bvh8's binary tree
    // stops at 3 with C_trav = C_isect, bvh's at 8 with C_trav = 3 C_isect). The bound on the area keeps
    // every plane's cost finite, as the sweep needs it to be for "a plane exists" to mean "a split exists".
    constexpr float kFiniteCostArea = 1e35f;  // x 2 sides x at most 255 tests, far below FLT_MAX
    if (fits_leaf && leaf_cost <= o_.traversal_cost && area <= kFiniteCostArea) {
      if (has_binned_plane(refs, begin, end, centroids)) return {};
      return {Split::Kind::ObjectMedian, centroids.largest_axis()};
    }

    Split best = best_binned_split(refs, begin, end, centroids, second_kind);
    if (best.kind == Split::Kind::None)  // centroid extent too small to bin on any axis
      return {Split::Kind::ObjectMedian, centroids.largest_axis()};
    // Compare with stopping here: both costs per unit of this node's area.
    const float split_cost = area > 0.0f ? o_.traversal_cost + o_.intersection_cost * best.cost / area : INFINITY;
    if (fits_leaf && leaf_cost <= split_cost) return {};
    return best;
  }

  // The mapping of centroids to bins on every axis, and which axes are usable: an extent of zero or one too
  // small for a finite scale cannot be binned.
  BinMapping bin_mapping(const Bounds3& centroids, std::array<bool, 3>& usable) const {
    const int bins = o_.bins;
    std::array<float, 3> scale{};
    for (int axis = 0; axis < 3; ++axis) {
      const float extent = centroids.hi[axis] - centroids.lo[axis];
      scale[static_cast<std::size_t>(axis)] = static_cast<float>(bins) / extent;
      usable[static_cast<std::size_t>(axis)] = extent > 0.0f && std::isfinite(scale[static_cast<std::size_t>(axis)]);
    }
    return {_mm_setr_ps(centroids.lo.x, centroids.lo.y, centroids.lo.z, 0.0f),
            _mm_setr_ps(scale[0], scale[1], scale[2], 0.0f), _mm_set1_ps(static_cast<float>(bins - 1)), bins};
  }

  // Whether best_binned_split() would find a plane: on some usable axis the primitives fall in at least
  // two bins (then the first of them has a plane after it, with both sides non-empty).
  bool has_binned_plane(const PrimRef* refs, std::size_t begin, std::size_t end, const Bounds3& centroids) const {
    std::array<bool, 3> usable{};
    const BinMapping map = bin_mapping(centroids, usable);
    alignas(16) std::int32_t first[4], k[4];
    __m128 lo, hi;
    map.bins_of(refs[begin], lo, hi, first);
    for (std::size_t i = begin + 1; i < end; ++i) {
      map.bins_of(refs[i], lo, hi, k);
      for (std::size_t axis = 0; axis < 3; ++axis)
        if (usable[axis] && k[axis] != first[axis]) return true;
    }
    return false;
  }

  // Bins the centroids on every axis whose extent allows it (one pass), then sweeps the bins-1 planes
  // between them. Split::cost is the un-normalized sum area(L) tests(L) + area(R) tests(R), tests counted
  // as in leaf_tests.
  Split best_binned_split(const PrimRef* range_refs, std::size_t begin, std::size_t end, const Bounds3& centroids,
                          std::uint32_t second_kind) const {
    std::array<bool, 3> usable{};
    const BinMapping map = bin_mapping(centroids, usable);
    const int bins = o_.bins;
    const std::span<const PrimRef> refs(range_refs, end);
    BinGrid grid;
    if (!o_.parallel || end - begin < kParallelRangeGrain) {
      bin_range(grid, refs, begin, end, map, second_kind_begin_, second_kind != 0, avx2_);
    } else {
      grid = reduce_chunks<BinGrid>(begin, end, [&](std::size_t b, std::size_t e) {
        BinGrid g;
        bin_range(g, refs, b, e, map, second_kind_begin_, second_kind != 0, avx2_);
        return g;
      }, [](BinGrid& acc, const BinGrid& part) { acc.merge(part); });
    }

    if (end - begin >= kDenseFrom) return best_plane_of_cleared_grid(grid, bins, usable);

    Split best;
    for (int axis = 0; axis < 3; ++axis) {
      if (!usable[static_cast<std::size_t>(axis)]) continue;
      // Only the planes right after an occupied bin are candidates: with bin k - 1 empty, plane k has the
      // same sides and cost as plane k - 1, which comes first and so wins the tie (strict <). The sweep
      // therefore runs over the occupied bins only, with the same folds in the same order as over all.
      const auto a = static_cast<std::size_t>(axis);
      int occupied[kMaxBins];
      int n_occupied = 0;
      for (std::uint32_t m = grid.used[a]; m != 0; m &= m - 1) occupied[n_occupied++] = __builtin_ctz(m);
      // right_cost[i] = area * primitive tests of the bins occupied[i..]
      float right_cost[kMaxBins];
      __m128 lo = grid.lo[a][occupied[n_occupied - 1]], hi = grid.hi[a][occupied[n_occupied - 1]];
      std::uint32_t count = 0, second = 0;
      for (int i = n_occupied - 1; i > 0; --i) {
        const int k = occupied[i];
        lo = extend_lo(lo, grid.lo[a][k]);
        hi = extend_hi(hi, grid.hi[a][k]);
        count += grid.count[a][k];
        second += grid.second_kind[a][k];
        right_cost[i] = half_area(lo, hi) * leaf_tests(count, second);
      }
      lo = grid.lo[a][occupied[0]];
      hi = grid.hi[a][occupied[0]];
      count = 0;
      second = 0;
      for (int i = 0; i + 1 < n_occupied; ++i) {
        const int k = occupied[i];
        lo = extend_lo(lo, grid.lo[a][k]);
        hi = extend_hi(hi, grid.hi[a][k]);
        count += grid.count[a][k];
        second += grid.second_kind[a][k];
        const float cost = half_area(lo, hi) * leaf_tests(count, second) + right_cost[i + 1];
        if (cost < best.cost) best = {Split::Kind::Bin, axis, k + 1, cost};
      }
    }
    return best;
  }

  // Splits refs[begin, end) and describes both sides. Large ranges are partitioned stably in parallel
  // chunks (count, then scatter into the other array: `in_scratch` flips), small ones in place; the
  // choice depends on the size only, so serial and parallel builds stay identical.
  std::size_t partition(PrimRef* refs, std::size_t begin, std::size_t end, const Bounds3& centroids, const Split& split,
                        RangeInfo& left, RangeInfo& right, bool& in_scratch) const {
    PrimRef* first = refs + begin;
    PrimRef* last = refs + end;
    std::size_t mid = end;
    switch (split.kind) {
      case Split::Kind::Bin: {
        // A primitive goes left when its bin on the split axis, computed as the binning did (same mapping,
        // BinMapping::bins_of), is below the plane: all three lanes at once, then the split axis's bit.
        std::array<bool, 3> usable{};
        const BinMapping map = bin_mapping(centroids, usable);
        const __m128i plane = _mm_set1_epi32(split.bin);
        const int axis = split.axis;
        const auto goes_left = [&](const PrimRef& r) {
          const __m128i below = _mm_cmplt_epi32(map.bins_of(r.lo4(), r.hi4()), plane);
          return ((_mm_movemask_ps(_mm_castsi128_ps(below)) >> axis) & 1) != 0;
        };
        if (end - begin >= kParallelRangeGrain) {
          PrimRef* const to = in_scratch ? home_ : scratch_;
          in_scratch = !in_scratch;
          return partition_in_chunks(refs, to, begin, end, goes_left, left, right);
        }
        return partition_in_place(refs, begin, end, goes_left, left, right);
      }
      case Split::Kind::ByKind:
        mid = static_cast<std::size_t>(
            std::stable_partition(first, last, [&](const PrimRef& r) { return r.id < second_kind_begin_; }) - refs);
        break;
      case Split::Kind::ObjectMedian: {
        // Ties broken by id, so the split (and the whole tree) does not depend on the partition algorithm.
        const int axis = split.axis;
        PrimRef* median = first + (last - first) / 2;
        std::nth_element(first, median, last, [axis](const PrimRef& a, const PrimRef& b) {
          const float ca = a.centroid()[axis], cb = b.centroid()[axis];
          return ca != cb ? ca < cb : a.id < b.id;
        });
        mid = static_cast<std::size_t>(median - refs);
        break;
      }
      case Split::Kind::None: break;
    }
    left = info_of(refs, begin, mid);
    right = info_of(refs, mid, end);
    return mid;
  }

  // Hoare partition that describes both sides on the way: every primitive is classified once and folded
  // into the side it ends on, so a small node needs one pass over its primitives instead of three.
  template <class Pred>
  std::size_t partition_in_place(PrimRef* refs, std::size_t begin, std::size_t end, const Pred& goes_left, RangeInfo& left,
                                 RangeInfo& right) const {
    left = RangeInfo{};
    right = RangeInfo{};
    PrimRef* lo = refs + begin;
    PrimRef* hi = refs + end;
    for (;;) {
      while (lo < hi && goes_left(*lo)) left.add(*lo++, second_kind_begin_);
      while (lo < hi && !goes_left(hi[-1])) right.add(*--hi, second_kind_begin_);
      if (lo == hi) break;
      // *lo belongs right and hi[-1] left.
      std::swap(*lo, *--hi);
      left.add(*lo++, second_kind_begin_);
      right.add(*hi, second_kind_begin_);
    }
    return static_cast<std::size_t>(lo - refs);
  }

  // Stable partition of from[begin, end) into to[begin, end), in fixed chunks: count each chunk's sides,
  // then scatter each chunk to where its sides start.
  template <class Pred>
  std::size_t partition_in_chunks(const PrimRef* from, PrimRef* to, std::size_t begin, std::size_t end, const Pred& goes_left,
                                  RangeInfo& left, RangeInfo& right) const {
    const std::size_t n = end - begin;
    const std::size_t chunks = (n + kRangeChunk - 1) / kRangeChunk;
    struct Part {
      std::size_t lefts = 0;
      RangeInfo left, right;
    };
    std::vector<Part> parts(chunks);
    const auto chunk_of = [&](std::size_t b) { return (b - begin) / kRangeChunk; };
    for_chunks(begin, end, [&](std::size_t b, std::size_t e) {
      Part& p = parts[chunk_of(b)];
      for (std::size_t i = b; i < e; ++i) {
        if (goes_left(from[i])) {
          ++p.lefts;
          p.left.add(from[i], second_kind_begin_);
        } else {
          p.right.add(from[i], second_kind_begin_);
        }
      }
    });

    std::vector<std::size_t> left_at(chunks), right_at(chunks);
    std::size_t lefts = 0;
    for (std::size_t c = 0; c < chunks; ++c) lefts += parts[c].lefts;
    std::size_t l = begin, r = begin + lefts;
    left = RangeInfo{};
    right = RangeInfo{};
    for (std::size_t c = 0; c < chunks; ++c) {
      left_at[c] = l;
      right_at[c] = r;
      l += parts[c].lefts;
      r += std::min(kRangeChunk, n - c * kRangeChunk) - parts[c].lefts;
      left.merge(parts[c].left);
      right.merge(parts[c].right);
    }
    for_chunks(begin, end, [&](std::size_t b, std::size_t e) {
      std::size_t li = left_at[chunk_of(b)], ri = right_at[chunk_of(b)];
      for (std::size_t i = b; i < e; ++i) to[goes_left(from[i]) ? li++ : ri++] = from[i];
    });
    return begin + lefts;
  }

  PrimRef* home_;                   // every range's primitives, except large ranges in the scratch array
  PrimRef* scratch_ = nullptr;      // the other array of large ranges' scatters (none for a small input)
  std::unique_ptr<PrimRef[]> scratch_owner_;  // freed between build_tree()'s two phases
  BvhNode* nodes_;
  std::uint32_t second_kind_begin_;
  const BvhBuildOptions& o_;
  bool avx2_;  // large ranges are binned by bin_range_avx2
};

}  // namespace

BvhTree build_bvh(std::span<const Bounds3> bounds, std::uint32_t second_kind_begin, const BvhBuildOptions& options, Isa isa) {
  validate(options);
  BvhTree tree;
  if (bounds.empty()) return tree;
  const std::size_t n = bounds.size();
  // Uninitialised (PrimRef is trivially constructible): every element is written right below.
  const std::unique_ptr<PrimRef[]> ref_storage(new PrimRef[n]);
  const std::span<PrimRef> refs(ref_storage.get(), n);
  const auto make_refs = [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) refs[i] = PrimRef{bounds[i].lo, static_cast<std::uint32_t>(i), bounds[i].hi, 0.0f};
  };
  if (options.parallel && n >= kParallelRangeGrain)
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kRangeChunk),
                      [&](const tbb::blocked_range<std::size_t>& r) { make_refs(r.begin(), r.end()); });
  else
    make_refs(0, n);

  // Uninitialised: build() writes every node it reports, and only those are read.
  static_assert(std::is_trivially_default_constructible_v<BvhNode>, "new[] must not initialise the nodes");
  const std::unique_ptr<BvhNode[]> nodes(new BvhNode[2 * refs.size() - 1]);
  Builder builder(refs, nodes.get(), second_kind_begin, options, isa);
  const std::size_t node_count = builder.build_tree(n, builder.info_of(refs.data(), 0, n));
  tree.nodes.reserve(node_count);
  builder.compact(0, 0, tree);

  tree.prim_order.resize(refs.size());
  for (std::size_t i = 0; i < refs.size(); ++i) tree.prim_order[i] = refs[i].id;
  tree.sah_cost = sah_cost(tree.nodes, options);
  return tree;
}

double sah_cost(std::span<const BvhNode> nodes, const BvhBuildOptions& options) {
  if (nodes.empty()) return 0.0;
  const auto area = [](const BvhNode& n) { return static_cast<double>(Bounds3{n.lo, n.hi}.half_area()); };
  const double root_area = area(nodes[0]);
  double cost = 0.0;
  for (const BvhNode& n : nodes) {
    const double weight = root_area > 0.0 ? area(n) / root_area : 1.0;
    const std::uint32_t spheres = n.is_sphere_leaf() ? n.prim_count() : 0u;
    cost += weight * (n.is_leaf() ? options.intersection_cost * static_cast<double>(leaf_tests(n.prim_count(), spheres))
                                  : options.traversal_cost);
  }
  return cost;
}

}  // namespace twinray
