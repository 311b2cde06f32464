#pragma once
// The small subtrees of the binned SAH builder, built by a full SAH sweep over sorted centroids instead of
// binning every node (docs/bvh-backend.md "Eleventh round"). Most nodes of bvh8's binary tree hold a few
// primitives; binning such a node (clear or mark 3 x 16 bins, sweep the occupied ones, partition by bin)
// cost about 2000 instructions. Here a subtree of at most kSweptMax primitives sorts its centroids once per
// axis (by rank, branch-free) and every node below sweeps its primitives in that order and splits the
// three sorted lists stably, so no node bins or re-sorts. Every binned plane of a node is one of the
// sweep's candidates (a bin index is a non-decreasing function of the centroid), so each node's split is
// at least as good under the SAH as the binned one; the leaf-or-split rules are the binned builder's.

#include "backends/bvh/bvh_binning.h"
#include "backends/bvh/bvh_build_options.h"
#include "backends/bvh/bvh_node.h"

#include <cstddef>

namespace twinray::bvh_binning {

// The largest range built by build_swept_subtree(); the sort is quadratic in it.
constexpr std::size_t kSweptMax = 12;

// Builds the subtree over refs[begin, end) (2 to kSweptMax primitives, all of the first kind) into
// nodes[at, ...) depth-first, as Builder::build() lays a serial subtree out (a node, its left subtree, its
// right subtree; a leaf's offset is its first primitive's index into refs), reorders refs[begin, end) into
// leaf order and returns the node count. Returns 0 and writes nothing when the range has a non-finite
// coordinate or centroid, or a box too large for finite costs: the binned path handles those. The tree
// depends on the range's contents and order only, never on `avx2` (which only picks the compiled kernel).
std::size_t build_swept_subtree(PrimRef* refs, std::size_t begin, std::size_t end, BvhNode* nodes, std::size_t at,
                                const BvhBuildOptions& options, bool avx2);

}  // namespace twinray::bvh_binning
