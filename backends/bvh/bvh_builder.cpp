#include "backends/bvh/bvh_builder.h"

#include "backends/bvh/bvh_binning.h"
#include "backends/bvh/bvh_builder_memory.h"
#include "backends/bvh/bvh_swept_subtree.h"

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

// From this depth on only object-median splits are made. Each halves the primitive count, so at most 32
// more levels (2^32 primitives) plus one split by kind follow: the tree stays within kBvhMaxDepth.
constexpr std::size_t kMedianOnlyDepth = kBvhMaxDepth - 1 - 33;
// Subtrees with fewer primitives are built on the calling thread: task overhead would dominate.
constexpr std::size_t kParallelGrain = 4096;
// Nodes with at least this many primitives bin and partition in parallel chunks of kRangeChunk (the
// top few levels, where the recursion alone has fewer subtrees than threads).
constexpr std::size_t kParallelRangeGrain = std::size_t{1} << 15;
constexpr std::size_t kRangeChunk = std::size_t{1} << 13;

using namespace bvh_binning;

class Builder {
 public:
  // `nodes` has room for 2 refs.size() - 1 nodes (build() writes them).
  Builder(std::span<PrimRef> refs, BvhNode* nodes, std::uint32_t second_kind_begin, const BvhBuildOptions& o, Isa isa)
      : home_(refs.data()), nodes_(nodes), second_kind_begin_(second_kind_begin), o_(o), avx2_(isa >= Isa::Avx2) {
    if (refs.size() >= kParallelRangeGrain) {
      // Uninitialised: a range is scattered into it before it is read.
      scratch_owner_ = BuildArray<PrimRef>(refs.size());
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

  // Moves the subtree at nodes_[at] depth-first to nodes_[next, ...) without the gaps the parallel build
  // left, with its child offsets rebased, and counts its leaves and depth on the way. In place: the gapped
  // tree is depth-first too (a node, then its left subtree's room, then its right subtree's), so the
  // nodes are read in increasing positions and a node's new position (the count of nodes before it) is
  // never after its old one; a write only lands on a node already read, or on a gap.
  void compact(std::size_t at, std::size_t depth, std::size_t& next, BvhTree& out) const {
    out.max_depth = std::max(out.max_depth, depth);
    const BvhNode node = nodes_[at];  // a copy: the write below may land on it
    const std::size_t index = next++;
    nodes_[index] = node;
    if (node.is_leaf()) {
      ++out.leaves;
      return;
    }
    compact(at + 1, depth + 1, next, out);
    nodes_[index].offset = static_cast<std::uint32_t>(next);
    compact(node.second_child(), depth + 1, next, out);
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
    const Bounds3 box = info.box();
    const bool mixed = info.second_kind != 0 && info.second_kind != n;
    std::vector<ChunkCounts> chunk_counts;  // per chunk of the binning: the partition needs no counting pass
    BinMapping map{};
    const Split split = choose_split(refs, begin, end, info, depth, mixed, map, &chunk_counts);
    RangeInfo left_info, right_info;
    bool children_in_scratch = in_scratch;
    const std::size_t mid =
        partition(refs, begin, end, map, split, info.second_kind != 0, left_info, right_info, children_in_scratch, chunk_counts);
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

    BvhNode& node = nodes_[at];
    // The box as BvhNode{box.lo, begin, box.hi, 0}: lanes 0-2 of the rows are the coordinates.
    _mm_store_ps(&node.lo.x, info.lo);
    node.offset = static_cast<std::uint32_t>(begin);
    _mm_store_ps(&node.hi.x, info.hi);
    node.count = 0;
    if (n == 1) {  // what choose_split() decides for one primitive, without its conversions
      node.count = 1u | (info.second_kind == 1 ? BvhNode::kSphereLeafBit : 0u);
      return 1;
    }
    // Small subtrees of one kind sweep their sorted centroids instead of binning each node
    // (bvh_swept_subtree.h); a range with a non-finite coordinate comes back (0) and is binned.
    if (n <= kSweptMax && info.second_kind == 0 && o_.split_method == BvhSplitMethod::BinnedSah &&
        depth + kSweptMax < kMedianOnlyDepth) {
      const std::size_t count = build_swept_subtree(home_, begin, end, nodes_, at, o_, avx2_);
      if (count != 0) return count;
    }

    BinMapping map{};
    const Split split = choose_split(home_, begin, end, info, depth, mixed, map);
    if (split.kind == Split::Kind::None) {
      node.count = static_cast<std::uint32_t>(n) | (info.second_kind == n ? BvhNode::kSphereLeafBit : 0u);
      return 1;
    }
    RangeInfo left_info, right_info;
    bool in_scratch = false;  // small ranges stay in place
    const std::size_t mid = partition(home_, begin, end, map, split, info.second_kind != 0, left_info, right_info, in_scratch, {});

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

  // `chunk_counts`, if given, receives the bin counts of every chunk of a large range that is split by
  // bins (see best_binned_split).
  // `map` receives the range's bin mapping when the split is by bins (partition() classifies with it).
  Split choose_split(const PrimRef* refs, std::size_t begin, std::size_t end, const RangeInfo& info, std::size_t depth, bool mixed,
                     BinMapping& map, std::vector<ChunkCounts>* chunk_counts = nullptr) const {
    const std::uint32_t second_kind = info.second_kind;
    const std::size_t n = end - begin;
    const bool fits_leaf = n <= static_cast<std::size_t>(o_.max_leaf_size);
    if (n == 1 || (fits_leaf && !mixed && (o_.split_method == BvhSplitMethod::ObjectMedian || depth >= kMedianOnlyDepth)))
      return {};
    if (fits_leaf && mixed) return {Split::Kind::ByKind};

    // Bounds3::extent() of the centroids, lane by lane (a range is never empty).
    const __m128 extent = _mm_sub_ps(info.c_hi, info.c_lo);
    const bool centroids_coincide = (_mm_movemask_ps(_mm_cmpeq_ps(extent, _mm_setzero_ps())) & 7) == 7;
    const auto median = [&] { return Split{Split::Kind::ObjectMedian, info.centroids().largest_axis()}; };
    if (o_.split_method == BvhSplitMethod::ObjectMedian || depth >= kMedianOnlyDepth || centroids_coincide) return median();

    const float area = half_area(info.lo, info.hi);  // Bounds3::half_area() operation for operation
    std::array<bool, 3> usable{};
    bool plane_exists = false;
    map = bin_mapping(extent, info.c_lo, usable, plane_exists);
    const float leaf_cost = o_.intersection_cost * leaf_tests(static_cast<std::uint32_t>(n), second_kind);
    // A node that may be a leaf and whose leaf costs no more than one interior step stays a leaf whenever a
    // binned split exists: the split's cost below is C_trav plus a non-negative term, never less than the
    // leaf's. Which split is best does not matter then, only whether there is one, so the sweep is skipped.
    // These are the most common calls (every leaf of 2 or more primitives is one: bvh8's binary tree
    // stops at 3 with C_trav = C_isect, bvh's at 8 with C_trav = 3 C_isect). The bound on the area keeps
    // every plane's cost finite, as the sweep needs it to be for "a plane exists" to mean "a split exists".
    constexpr float kFiniteCostArea = 1e35f;  // x 2 sides x at most 255 tests, far below FLT_MAX
    if (fits_leaf && leaf_cost <= o_.traversal_cost && area <= kFiniteCostArea) {
      if (plane_exists) return {};
      return median();
    }

    Split best = best_binned_split(refs, begin, end, map, usable, second_kind, chunk_counts);
    if (best.kind == Split::Kind::None) return median();  // centroid extent too small to bin on any axis
    // Compare with stopping here: both costs per unit of this node's area.
    const float split_cost = area > 0.0f ? o_.traversal_cost + o_.intersection_cost * best.cost / area : INFINITY;
    if (fits_leaf && leaf_cost <= split_cost) return {};
    return best;
  }

  // The mapping of centroids to bins on every axis (centroid extent and lower bound in SSE rows), and which
  // axes are usable: an extent of zero or one too small for a finite scale cannot be binned. Lane by lane
  // the scalar `bins / extent` and `extent > 0 && isfinite(scale)`.
  // `plane_exists`: whether best_binned_split() would find a plane on a range of two or more primitives,
  // decided without binning them: exactly when some axis's extent is also finite. On such an axis the
  // primitive whose centroid is the lower bound maps to bin 0 ((c - lo) scale = 0), and the one whose
  // centroid is the upper bound to min(extent scale, bins - 1) >= 1 (extent and bins / extent are normal
  // floats, so their rounded product is bins within a few ulps): two occupied bins, so the plane after the
  // first has both sides non-empty. A usable axis with an infinite extent has scale 0, and every centroid
  // there maps to bin 0 ((c - lo) 0 is 0 or NaN, and a NaN lands in bin 0).
  BinMapping bin_mapping(__m128 extent, __m128 c_lo, std::array<bool, 3>& usable, bool& plane_exists) const {
    const __m128 bins = _mm_set1_ps(static_cast<float>(o_.bins));
    const __m128 scale = _mm_div_ps(bins, extent);
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
    const __m128 finite_scale = _mm_cmplt_ps(_mm_and_ps(scale, abs_mask), inf);
    const __m128 usable_lanes = _mm_and_ps(_mm_cmpgt_ps(extent, _mm_setzero_ps()), finite_scale);
    const int usable_mask = _mm_movemask_ps(usable_lanes);
    for (std::size_t axis = 0; axis < 3; ++axis) usable[axis] = (usable_mask >> axis & 1) != 0;
    plane_exists = (_mm_movemask_ps(_mm_and_ps(usable_lanes, _mm_cmplt_ps(_mm_and_ps(extent, abs_mask), inf))) & 7) != 0;
    const __m128 xyz_lanes = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));  // the fourth lane 0, as before
    return {_mm_and_ps(c_lo, xyz_lanes), _mm_and_ps(scale, xyz_lanes), _mm_set1_ps(static_cast<float>(o_.bins - 1)), o_.bins};
  }

  // Bins the centroids on every axis whose extent allows it (one pass), then sweeps the bins-1 planes
  // between them. Split::cost is the un-normalized sum area(L) tests(L) + area(R) tests(R), tests counted
  // as in leaf_tests. A large range (kParallelRangeGrain or more) is binned in fixed chunks of kRangeChunk,
  // one grid each, merged in chunk order; each chunk's counts go to `chunk_counts` when it is given.
  Split best_binned_split(const PrimRef* range_refs, std::size_t begin, std::size_t end, const BinMapping& map,
                          const std::array<bool, 3>& usable, std::uint32_t second_kind,
                          std::vector<ChunkCounts>* chunk_counts) const {
    const int bins = o_.bins;
    const std::span<const PrimRef> refs(range_refs, end);
    BinGrid grid;
    if (end - begin < kParallelRangeGrain) {
      bin_range(grid, refs, begin, end, map, second_kind_begin_, second_kind != 0, avx2_);
    } else {
      // In chunks serially too: a merged grid differs from one binned in a single pass at most in the sign
      // of a zero coordinate of a bin's box, which changes no area, so the tree is the same either way.
      const std::size_t chunks = (end - begin + kRangeChunk - 1) / kRangeChunk;
      std::vector<BinGrid> parts(chunks);
      for_chunks(begin, end, [&](std::size_t b, std::size_t e) {
        bin_range(parts[(b - begin) / kRangeChunk], refs, b, e, map, second_kind_begin_, second_kind != 0, avx2_);
      });
      grid = parts[0];
      for (std::size_t c = 1; c < chunks; ++c) grid.merge(parts[c]);
      if (chunk_counts != nullptr) {
        chunk_counts->resize(chunks);
        for (std::size_t c = 0; c < chunks; ++c) (*chunk_counts)[c] = ChunkCounts::of(parts[c], bins);
      }
    }

    if (end - begin >= kDenseFrom) return best_plane_of_cleared_grid(grid, bins, usable, avx2_);
    return best_plane_of_occupied_bins(grid, usable, second_kind != 0, avx2_);
  }

  // Splits refs[begin, end) and describes both sides. Large ranges are partitioned stably in parallel
  // chunks (scattered into the other array: `in_scratch` flips; where each chunk's sides go follows from
  // the binning's `chunk_counts`), small ones in place; the choice depends on the size only, so serial and
  // parallel builds stay identical.
  std::size_t partition(PrimRef* refs, std::size_t begin, std::size_t end, const BinMapping& map, const Split& split,
                        bool second_kind_present, RangeInfo& left, RangeInfo& right, bool& in_scratch,
                        std::span<const ChunkCounts> chunk_counts) const {
    PrimRef* first = refs + begin;
    PrimRef* last = refs + end;
    std::size_t mid = end;
    switch (split.kind) {
      case Split::Kind::Bin: {
        // A primitive goes left when its bin on the split axis, computed as the binning did (same mapping,
        // BinMapping::bins_of), is below the plane: all three lanes at once, then the split axis's bit.
        const int axis = split.axis;
        if (end - begin >= kParallelRangeGrain) {
          PrimRef* const to = in_scratch ? home_ : scratch_;
          in_scratch = !in_scratch;
          return partition_in_chunks(refs, to, begin, end, map, chunk_counts, split, second_kind_present, left, right);
        }
        return partition_small_range(refs, begin, end, map, axis, split.bin, second_kind_begin_, second_kind_present, left, right,
                                     avx2_);
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

  // Stable partition of from[begin, end) into to[begin, end), in fixed chunks: each chunk's left count is
  // the sum of its bins below the plane (the binning's own counts, so no counting pass reads the range
  // again), each chunk scatters to where its sides start and describes them on the way; the descriptions
  // are merged in chunk order.
  std::size_t partition_in_chunks(const PrimRef* from, PrimRef* to, std::size_t begin, std::size_t end, const BinMapping& map,
                                  std::span<const ChunkCounts> chunk_counts, const Split& split, bool second_kind_present,
                                  RangeInfo& left, RangeInfo& right) const {
    const std::size_t n = end - begin;
    const std::size_t chunks = (n + kRangeChunk - 1) / kRangeChunk;
    if (chunk_counts.size() != chunks) throw std::logic_error("bvh: a large range was partitioned without its bin counts");
    std::vector<std::size_t> left_at(chunks), right_at(chunks);
    std::size_t lefts = 0;
    for (std::size_t c = 0; c < chunks; ++c) lefts += chunk_counts[c].below(split.axis, split.bin);
    std::size_t l = begin, r = begin + lefts;
    for (std::size_t c = 0; c < chunks; ++c) {
      const std::size_t chunk_lefts = chunk_counts[c].below(split.axis, split.bin);
      left_at[c] = l;
      right_at[c] = r;
      l += chunk_lefts;
      r += std::min(kRangeChunk, n - c * kRangeChunk) - chunk_lefts;
    }
    struct Sides {
      RangeInfo left, right;
    };
    std::vector<Sides> sides(chunks);
    const auto chunk_of = [&](std::size_t b) { return (b - begin) / kRangeChunk; };
    for_chunks(begin, end, [&](std::size_t b, std::size_t e) {
      Sides& part = sides[chunk_of(b)];
      scatter_range(from, to, b, e, left_at[chunk_of(b)], right_at[chunk_of(b)], map, split.axis, split.bin, second_kind_begin_,
                    second_kind_present, part.left, part.right, avx2_);
    });
    left = RangeInfo{};
    right = RangeInfo{};
    for (const Sides& part : sides) {
      left.merge(part.left);
      right.merge(part.right);
    }
    return begin + lefts;
  }

  PrimRef* home_;                   // every range's primitives, except large ranges in the scratch array
  PrimRef* scratch_ = nullptr;      // the other array of large ranges' scatters (none for a small input)
  BuildArray<PrimRef> scratch_owner_;  // freed between build_tree()'s two phases
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
  // Uninitialised (PrimRef is trivially constructible): every element is written right below. On huge
  // pages, as the other large arrays of the build (bvh_builder_memory.h).
  const BuildArray<PrimRef> ref_storage(n);
  const std::span<PrimRef> refs(ref_storage.get(), n);
  const auto make_refs = [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) refs[i] = PrimRef{bounds[i].lo, static_cast<std::uint32_t>(i), bounds[i].hi, 0.0f};
  };
  if (options.parallel && n >= kParallelRangeGrain)
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kRangeChunk),
                      [&](const tbb::blocked_range<std::size_t>& r) { make_refs(r.begin(), r.end()); });
  else
    make_refs(0, n);

  // Uninitialised (BuildAllocator): build() writes every node it reports, and only those are read; the
  // gapped tree is compacted in place into the same vector, so no second node array is allocated.
  tree.nodes.resize(2 * refs.size() - 1);
  Builder builder(refs, tree.nodes.data(), second_kind_begin, options, isa);
  const std::size_t node_count = builder.build_tree(n, builder.info_of(refs.data(), 0, n));
  // The compacting copy (one serial depth-first walk) and the primitive order are independent: on two or
  // more threads the latter runs beside the former.
  const auto compact = [&] {
    std::size_t next = 0;
    builder.compact(0, 0, next, tree);
    tree.nodes.resize(node_count);  // a shrink: no reallocation
    // The pages past the compacted tree go back to the system (the worst case's room is about a quarter
    // of the array on bvh8's binary trees): the gapped array lives on through the collapse and the gather,
    // and without this the peak resident memory of a 4M-triangle bvh8 build rose by 3 to 10%.
    release_build_memory_tail(tree.nodes.data(), node_count * sizeof(BvhNode), tree.nodes.capacity() * sizeof(BvhNode));
  };
  const auto order = [&] {
    resize_on_huge_pages(tree.prim_order, refs.size());
    const auto copy_ids = [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) tree.prim_order[i] = refs[i].id;
    };
    if (options.parallel && n >= kParallelRangeGrain)  // like the references above: no serial pass over N
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kRangeChunk),
                        [&](const tbb::blocked_range<std::size_t>& r) { copy_ids(r.begin(), r.end()); });
    else
      copy_ids(0, n);
  };
  if (options.parallel) {
    tbb::parallel_invoke(compact, order);
  } else {
    compact();
    order();
  }
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
