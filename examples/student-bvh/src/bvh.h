#pragma once
// Your bounding volume hierarchy.
//
// The tree is a flat array of nodes. Every node covers the primitives primitives[start, start + size); an
// interior node has two children, nodes[l] and nodes[r], which split its range between them; a leaf has
// l == r (and no children). Reorder `primitives` as you build, so that every node's primitives are
// contiguous.
//
// twinray calls build() once, then hit() and any_hit() from many threads at once: both are const and must
// not modify the BVH (keep your traversal stack in a local variable).

#include "bbox.h"
#include "primitives.h"
#include "ray.h"

#include <cstddef>
#include <vector>

struct Node {
  BBox bbox;
  std::size_t start = 0, size = 0;  // the primitives this node covers
  std::size_t l = 0, r = 0;         // children; l == r for a leaf
  bool is_leaf() const { return l == r; }
};

class BVH {
 public:
  // Builds the tree over `primitives` (which the BVH then owns), with at most max_leaf_size primitives per
  // leaf where a split is possible.
  void build(std::vector<Primitive>&& primitives, std::size_t max_leaf_size = 4);

  // The closest hit within ray.dist_bounds (Trace::closer decides ties), or a trace with hit == false.
  Trace hit(const Ray& ray, TraversalStats& stats) const;
  // Whether anything at all is hit within ray.dist_bounds. Stop at the first hit: this is what shadow rays ask.
  bool any_hit(const Ray& ray, TraversalStats& stats) const;

  // The surface area heuristic cost of the tree, in the unit model twinray compares (docs/plugin-abi.md):
  // the sum over interior nodes of area(node) / area(root), plus the sum over leaves of
  // area(leaf) / area(root) * (primitives in the leaf). 0 means "not reported".
  double sah_cost() const;

  std::size_t node_count() const { return nodes.size(); }

 private:
  std::vector<Primitive> primitives;
  std::vector<Node> nodes;
  std::size_t root_idx = 0;

  // Appends a node and returns its index.
  std::size_t new_node(const BBox& bbox, std::size_t start, std::size_t size, std::size_t l, std::size_t r);
};
