#include "backends/wide/wide_any_order.h"

#include "core/geometry/hit.h"
#include "core/geometry/ray.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cstddef>
#include <limits>

namespace twinray {
namespace {

// A small fixed generator (64-bit LCG, Knuth's MMIX constants, the top 24 bits as a float in [0, 1)): the
// probe, and so the choice, is the same on every run and platform.
struct ProbeRandom {
  std::uint64_t state = 0x9e3779b97f4a7c15ull;
  float unit() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<float>(state >> 40) * 0x1p-24f;
  }
  glm::vec3 in(const glm::vec3& lo, const glm::vec3& hi) {
    glm::vec3 p;
    for (int a = 0; a < 3; ++a) p[a] = lo[a] + unit() * (hi[a] - lo[a]);
    return p;
  }
};

// The centre of a leaf child's box, from a node drawn at random; false when that node has no leaf child.
bool leaf_centre(std::span<const WideNode> nodes, ProbeRandom& random, glm::vec3& centre) {
  const WideNode& node = nodes[static_cast<std::size_t>(random.unit() * static_cast<float>(nodes.size())) % nodes.size()];
  for (int s = 0; s < kWideWidth; ++s) {
    if (!(node.lo[0][s] <= node.hi[0][s]) || !WideRef::is_leaf(node.child[s])) continue;
    for (int a = 0; a < 3; ++a) centre[a] = 0.5f * (node.lo[a][s] + node.hi[a][s]);
    return true;
  }
  return false;
}

}  // namespace

AnyHitProbe probe_any_hit_order(std::span<const WideNode> nodes, const PrimitiveStore& prims,
                                const WideKernels& stored, const WideKernels& nearest) {
  AnyHitProbe probe;
  if (nodes.empty()) return probe;
  // The scene's bounds: the union of the root's boxes, padded by a tenth of the diagonal on every side.
  glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
  for (int s = 0; s < kWideWidth; ++s)
    if (nodes[0].lo[0][s] <= nodes[0].hi[0][s])
      for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], nodes[0].lo[a][s]), hi[a] = std::max(hi[a], nodes[0].hi[a][s]);
  const glm::vec3 pad = 0.1f * (hi - lo);
  lo -= pad;
  hi += pad;
  const glm::vec3 centre = 0.5f * (lo + hi);
  const float radius = glm::length(hi - lo);  // a sphere well outside the padded box

  ProbeRandom random;
  QueryStats stored_stats, nearest_stats;
  const WideView view{nodes.data(), &prims};
  // Bounded tries: a scene that few rays hit still ends the probe.
  for (std::uint32_t tries = 0; probe.segments < kWideProbeSegments && tries < 8 * kWideProbeSegments; ++tries) {
    // A first hit of a ray from outside the scene toward a point in it...
    glm::vec3 from = random.in(glm::vec3(-1.0f), glm::vec3(1.0f));
    if (glm::length(from) < 1e-3f) continue;
    Ray look;
    look.org = centre + radius * glm::normalize(from);
    // Aimed at the centre of a leaf's box, so that nearly every look finds a surface (aimed at random points
    // of the box, nine in ten missed the hairball, and those misses were most of the probe's cost).
    glm::vec3 aim;
    if (!leaf_centre(nodes, random, aim)) continue;
    look.dir = aim - look.org;
    Hit hit;
    if (!stored.intersect_ids(view, look, hit, nullptr)) continue;
    // ...joined to a point in the box: a shadow ray toward a light somewhere in the scene.
    Ray segment;
    segment.org = look.org + hit.t * look.dir;
    segment.dir = random.in(lo, hi) - segment.org;
    segment.tmin = 0.0f;
    segment.tmax = 1.0f;
    if (segment.dir == glm::vec3(0.0f)) continue;
    stored.occluded(view, segment, &stored_stats);
    nearest.occluded(view, segment, &nearest_stats);
    ++probe.segments;
  }
  auto cost = [](const QueryStats& s) {
    return static_cast<double>(s.nodes_visited) + kWideProbePrimitiveWeight * static_cast<double>(s.primitives_tested);
  };
  probe.stored_cost = cost(stored_stats);
  probe.nearest_cost = cost(nearest_stats);
  if (probe.nearest_cost < kWideProbeMargin * probe.stored_cost) probe.chosen = AnyHitOrder::kNearest;
  return probe;
}

}  // namespace twinray
