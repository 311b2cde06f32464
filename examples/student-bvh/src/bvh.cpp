#include "bvh.h"

#include <algorithm>
#include <utility>

std::size_t BVH::new_node(const BBox& bbox, std::size_t start, std::size_t size, std::size_t l, std::size_t r) {
  Node n;
  n.bbox = bbox;
  n.start = start;
  n.size = size;
  n.l = l;
  n.r = r;
  nodes.push_back(n);
  return nodes.size() - 1;
}

void BVH::build(std::vector<Primitive>&& prims, std::size_t max_leaf_size) {
  primitives = std::move(prims);
  nodes.clear();
  root_idx = 0;
  (void)max_leaf_size;

  // TODO: build the tree.
  //  1. The root covers every primitive: new_node(box of all primitives, 0, primitives.size(), 0, 0).
  //  2. Split a node whose size is above max_leaf_size: choose an axis and a position with the surface area
  //     heuristic (sort the primitive centroids into ~12 buckets along each axis and price every split
  //     between buckets: area(left) * count(left) + area(right) * count(right)), std::partition its range of
  //     `primitives` there, and give it two children covering the two halves.
  //  3. Careful: when every centroid is the same point (twinray's build checks have 10,000 identical
  //     triangles), no split separates anything. Make sure your recursion still ends.
  //  4. Keep nodes[] indices, not pointers or references: new_node() may reallocate the vector.
}

Trace BVH::hit(const Ray& ray, TraversalStats& stats) const {
  Trace closest;
  (void)ray;
  (void)stats;
  // TODO: find the closest hit.
  //  - Start at nodes[root_idx] (when there are nodes); skip a node whose box the ray misses.
  //  - In a leaf, test each primitive: closest = Trace::closer(closest, primitives[i].hit(ray)).
  //  - Visit the nearer child first, and skip a child whose box starts beyond the closest hit found so far.
  //  - Use a local stack (an array of node indices), never a member: hit() runs on many threads at once.
  //  - Count stats.nodes_visited (boxes tested) and stats.primitives_tested if you want twinray's figures.
  return closest;
}

bool BVH::any_hit(const Ray& ray, TraversalStats& stats) const {
  (void)ray;
  (void)stats;
  // TODO: like hit(), but return true as soon as any primitive is hit within ray.dist_bounds.
  return false;
}

double BVH::sah_cost() const {
  // TODO (optional, for the tree-quality check): the unit-model SAH cost described in bvh.h.
  return 0.0;
}
