#pragma once
// The binned SAH's building blocks (Wald 2007, docs/bvh-backend.md "Build"): the primitive reference the
// builder moves, what a node's split decision knows about its primitives, the bins of all three axes and how
// a range maps to them, binning a range (SSE, or the AVX2 kernel on dense ranges), the three-axis sweeps of
// a cleared and of a lazily filled grid, and partitioning a range at a plane (in place, or scattered into
// another array). bvh_builder.cpp decides splits with them; everything here folds boxes exactly like
// Bounds3::extend, so the trees do not depend on which path computed them. Each of these runs as SSE2 code
// or as an AVX2 build (`avx2`: the builder's Isa) of the same operations, dispatched at run time.

#include "backends/bvh/primitive_store.h"
#include "core/geometry/bounds.h"

#include <glm/vec3.hpp>

#include <immintrin.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <type_traits>

namespace twinray::bvh_binning {

constexpr int kMaxBins = 32;

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

// How many primitives of one chunk's grid lie below each plane, on each axis: what a stable partition of
// a large range in chunks needs to know where each chunk's two sides go, read off the binning's counts
// instead of classifying the chunk's primitives once more.
struct ChunkCounts {
  std::uint32_t below_plane[3][kMaxBins + 1];  // [axis][k]: primitives in bins [0, k)

  static ChunkCounts of(const BinGrid& g, int bins) {
    ChunkCounts c;
    for (int a = 0; a < 3; ++a) {
      c.below_plane[a][0] = 0;
      for (int k = 0; k < bins; ++k)  // a bin not marked used holds nothing (and its count is not set)
        c.below_plane[a][k + 1] = c.below_plane[a][k] + ((g.used[a] >> k & 1u) != 0 ? g.count[a][k] : 0u);
    }
    return c;
  }
  std::size_t below(int axis, int plane) const {
    return below_plane[static_cast<std::size_t>(axis)][static_cast<std::size_t>(plane)];
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

// Splits refs[begin, end) in place where the primitives' bins on `axis` (BinMapping::bins_of, as binned)
// are below `plane`, and describes both sides on the way: a Hoare partition, every primitive classified once
// and folded into the side it ends on, so a small node needs one pass over its primitives instead of three.
// Returns the end of the left side. `second_kind_present`: the range may hold primitives of the second kind
// (otherwise both sides count none without testing ids). `avx2`: the AVX2 build of the same operations
// (the same result).
std::size_t partition_small_range(PrimRef* refs, std::size_t begin, std::size_t end, const BinMapping& map, int axis, int plane,
                                  std::uint32_t second_kind_begin, bool second_kind_present, RangeInfo& left, RangeInfo& right,
                                  bool avx2);

// Scatters from[b, e) stably into `to`, the primitives partition_small_range() would put left from to[left_at]
// on and the others from to[right_at] on, and describes both sides (folded in the order of `from`).
// `second_kind_present` as for partition_small_range(). `avx2`: the AVX2 build of the same operations (the
// same result).
void scatter_range(const PrimRef* from, PrimRef* to, std::size_t b, std::size_t e, std::size_t left_at, std::size_t right_at,
                   const BinMapping& map, int axis, int plane, std::uint32_t second_kind_begin, bool second_kind_present,
                   RangeInfo& left, RangeInfo& right, bool avx2);

// Clearing 3 x 16 bins costs about as much as the branches of binning 32 primitives lazily; from the same
// size on, sweeping the cleared grid's three axes at once beats sweeping the occupied bins one axis at a
// time (from 16 or 24 it cost more instructions, docs/bvh-backend.md).
constexpr std::size_t kDenseFrom = 32;

// Bins refs[b, e) into the unused grid g: ranges of kDenseFrom primitives or more clear the grid first and
// bin without testing `used` (with the AVX2 kernel when `avx2`), smaller ones mark the bins they fill;
// primitives of the second kind (ids from second_kind_begin) are counted when `second_kind_present`.
void bin_range(BinGrid& g, std::span<const PrimRef> refs, std::size_t b, std::size_t e, const BinMapping& map,
               std::uint32_t second_kind_begin, bool second_kind_present, bool avx2);

// The best plane of a cleared grid (every bin initialised, see BinGrid::clear) on the usable axes. The
// three axes are swept at once, one SSE lane each: a bin's three boxes are transposed so that a vector
// holds one coordinate of the three axes' bins. The costs are computed lane for lane with the operations,
// in the order, of the scalar sweep below (half_area, leaf_tests), so they are bit-identical to it, and
// the winner is the first minimum in (axis, plane) order, as the scalar sweep's strict < finds it. Every
// plane is a candidate: a plane after an empty bin has the sides, hence the cost, of the plane before it
// and loses the tie; a plane with an empty side costs inf * 0 = NaN, which never compares less. Worth it
// for large ranges, whose bins are mostly occupied; small ranges sweep their few occupied bins instead.
// `avx2`: the AVX2 build of the same operations (same bits).
Split best_plane_of_cleared_grid(const BinGrid& g, int bins, const std::array<bool, 3>& usable, bool avx2);

// The best plane of a lazily filled grid (a small range's: only bins marked used are set) on the usable
// axes, bit-identical to sweeping each axis's occupied bins in turn in scalar code. Only the planes right
// after an occupied bin are candidates: with bin k - 1 empty, plane k has the sides and cost of plane
// k - 1, which comes first and wins the tie (strict <). The three axes are swept at once, lane a walking
// axis a's i-th occupied bin at step i (transposed as in best_plane_of_cleared_grid); an axis with fewer
// occupied bins is padded with empty bins, which leave a side's box and counts as they are, and its lanes
// past its last plane never win. Most calls of a bvh8 build are ranges of a few primitives (about five
// occupied bins per axis on the dragon), where the scalar sweeps were a sixth of the build.
// `second_kind_present`: the grid counts primitives of the second kind (else its counts are read as 0);
// `avx2`: run the AVX2 build of the same operations (same bits).
Split best_plane_of_occupied_bins(const BinGrid& g, const std::array<bool, 3>& usable, bool second_kind_present, bool avx2);

}  // namespace twinray::bvh_binning
