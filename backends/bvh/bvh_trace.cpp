// The traced queries of BvhBackend (bvh_backend.h): the production traversal with an observer that records
// every node entered. In a file of their own so that the observer's instantiations do not change how the
// compiler inlines the untraced ones in bvh_backend.cpp: the hot path compiles exactly as without them.

#include "backends/bvh/bvh_backend.h"
#include "backends/bvh/bvh_traversal.h"

namespace twinray {

namespace {

struct RecordingObserver {
  std::vector<BvhVisit>* visits;
  void enter(std::uint32_t node, float tmax) const { visits->push_back({node, tmax}); }
};

}  // namespace

bool BvhBackend::intersect_traced(const Ray& ray, Hit& hit, std::vector<BvhVisit>& visits, QueryStats* stats) const {
  visits.clear();
  if (stats) ++stats->queries;
  hit = Hit{};
  if (!is_valid_ray(ray)) return false;
  const BvhView view{nodes_, &prims_};
  const RecordingObserver observer{&visits};
  switch (kinds_) {
    case Kinds::Triangles: return bvh_intersect<true, false>(view, ray, hit, stats, observer);
    case Kinds::Spheres: return bvh_intersect<false, true>(view, ray, hit, stats, observer);
    case Kinds::Mixed: return bvh_intersect<true, true>(view, ray, hit, stats, observer);
    case Kinds::None: break;
  }
  return false;
}

bool BvhBackend::occluded_traced(const Ray& ray, std::vector<BvhVisit>& visits, QueryStats* stats) const {
  visits.clear();
  if (stats) ++stats->queries;
  if (!is_valid_ray(ray)) return false;
  const BvhView view{nodes_, &prims_};
  const RecordingObserver observer{&visits};
  switch (kinds_) {
    case Kinds::Triangles: return bvh_occluded<true, false>(view, ray, stats, observer);
    case Kinds::Spheres: return bvh_occluded<false, true>(view, ray, stats, observer);
    case Kinds::Mixed: return bvh_occluded<true, true>(view, ray, stats, observer);
    case Kinds::None: break;
  }
  return false;
}

}  // namespace twinray
