#pragma once
// Collapsing the binary SAH tree into 8-wide nodes by cost.
//
// Method: the dynamic program of Ylitie, Karras and Laine, "Efficient incoherent ray traversal on GPUs
// through compressed wide BVHs" (HPG 2017), section 4.1. For every binary node n and every j = 1..8 it
// finds the cheapest way to hand the subtree of n to a wide parent as at most j child slots, each slot a
// leaf or a wide node of its own:
//     cost(n, 1) = min( leaf(n), A(n) c_node + split(n, 8) )
//     cost(n, j) = min( cost(n, j - 1), split(n, j) )                 j >= 2
//     split(n, j) = min over k in 1..j-1 of cost(left, k) + cost(right, j - k)
//     leaf(n)    = A(n) c_block blocks(n) + c_pad empty_lanes(n), when n's primitives may form one leaf
// with A the surface area (the probability of a ray hitting n's box is proportional to it), c_node the cost
// of one wide node visit (eight boxes tested at once) and c_block the cost of one triangle-block test.
// Two terms extend the paper's model (measurements in docs/bvh-backend.md): c_pad prices the empty lanes
// of a leaf's last block, the memory small leaves waste (scaled by A(root) / N, so that it only outweighs
// the speed terms where leaves are small, in dense regions), and A(n) may carry a volume term,
// A(n) + c_vol V(n) A(root) / V(root): a secondary ray starts on a surface, inside the boxes around that
// surface, and visits them whatever their area, which the area alone (rays from outside) misses; interior
// views and scenes with a ground plane are made of such rays.
// So the collapse does not just pull up the largest children (Embree's builders) or merge by area alone:
// it decides per subtree whether a level of boxes pays for itself and where whole subtrees are cheaper as
// one leaf, which a greedy pass cannot see.
//
// Children are stored larger weight (area plus the volume term) first: any-hit traversal visits them in
// stored order, which tries the child most likely to hold an occluder first (Nah and Manocha, "SATO:
// surface area traversal order for shadow ray tracing", CGF 2014); closest-hit traversal sorts by entry
// distance instead.

#include "backends/bvh/bvh_builder.h"
#include "backends/wide/wide_node.h"

#include <cstdint>
#include <vector>

namespace twinray {

struct WideCollapseOptions {
  // Cost of visiting one wide node and of testing one block of four triangles (or one sphere), in the
  // same arbitrary unit; only the ratio matters. A block test costs two node visits since every candidate
  // the edge test accepts is refined to a certified t (about 90 instructions each); see
  // docs/bvh-backend.md ("Cost model") for the measurements.
  float node_cost = 1.0f;
  float block_cost = 2.0f;
  // Cost of one padded (empty) lane of a leaf's last triangle block, in units of block_cost times the
  // root's area over the primitive count: a memory price that only small leaves of dense regions notice.
  float padding_cost = 0.25f;
  // Weight of a box's volume beside its surface area in the probability that a ray visits it, relative to
  // the root's (a box's weight is A + volume_cost V A(root) / V(root)): rays that start inside a box (on
  // the surfaces of an interior view) visit it whatever its area.
  float volume_cost = 2.0f;
  // Largest leaf the collapse may form by merging a binary subtree (1..16 primitives); binary leaves are
  // kept whatever their size.
  int max_leaf_size = 8;
};

// A leaf of the wide tree: the range of the binary tree's prim_order it covers.
struct WideLeafRange {
  std::uint32_t first_prim;
  std::uint32_t count;
  bool spheres;
};

struct WideTree {
  // nodes[0] is the root. Inner children are written as node indices and leaf children as
  // WideRef::kLeafBit | index into `leaves`, for the backend to replace with byte offsets (wide_inner_ref) and
  // references into its primitive store. Leaves are numbered in node order (node
  // by node, slot by slot), the order in which the backend stores their primitives.
  std::vector<WideNode> nodes;
  std::vector<WideLeafRange> leaves;
  std::size_t max_depth = 0;
  double sah_cost = 0.0;  // the root's cost in the collapse's units, divided by the root's area
};

// Throws std::invalid_argument for out-of-range options. An empty binary tree gives an empty wide tree.
// Runs in TBB tasks over independent subtrees; the tree is the same on any number of threads.
void validate(const WideCollapseOptions& options);
WideTree collapse_to_wide(const BvhTree& binary, const WideCollapseOptions& options);

}  // namespace twinray
