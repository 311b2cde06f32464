#include "harness/grade/tree_cost.h"

#include "backends/bvh/bvh_backend.h"

#include <vector>

namespace twinray::grade {

double sah_cost_unit_model(std::span<const TreeNodeCost> nodes) {
  if (nodes.empty()) return 0.0;
  const double root = nodes[0].box.half_area();
  double cost = 0.0;
  for (const TreeNodeCost& n : nodes) {
    // A flat or point-like root has no area to weigh by: every node then counts fully.
    const double weight = root > 0.0 ? static_cast<double>(n.box.half_area()) / root : 1.0;
    cost += weight * (n.primitives == 0 ? 1.0 : static_cast<double>(n.primitives));
  }
  return cost;
}

double reference_sah_cost(const SceneGeometry& geometry) {
  BvhBuildOptions options;
  // The builder's own costs set to the model's 1:1, so its splits aim at the same optimum.
  options.traversal_cost = 1.0f;
  options.intersection_cost = 1.0f;
  BvhBackend bvh(options);
  bvh.build(geometry);
  std::vector<TreeNodeCost> nodes;
  nodes.reserve(bvh.nodes().size());
  for (const BvhNode& n : bvh.nodes()) nodes.push_back({Bounds3{n.lo, n.hi}, n.is_leaf() ? n.prim_count() : 0u});
  return sah_cost_unit_model(nodes);
}

}  // namespace twinray::grade
