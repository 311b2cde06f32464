// The traced queries of BvhBackend (bvh_backend.h): the production traversal (bvh_traversal.inl) with an
// observer that records every node entered. Compiled here once more, on the portable SSE2 path, so the
// kernels of bvh_kernels_<isa>.cpp stay exactly as they are; every path gives bit-identical answers and
// visits the same nodes (the box tests agree bit for bit, bvh_kernels.h).

#include "backends/bvh/bvh_backend.h"

#include "backends/bvh/ray_box.h"
#include "backends/bvh/bvh_leaf.h"
#include "core/intersect/sphere_robust.h"
#include "core/intersect/triangle_watertight.h"

#include <algorithm>
#include <cstdint>
#include <type_traits>

namespace twinray {

namespace bvh_trace {

#define TWINRAY_KERNEL
#define TWINRAY_BOX_PAIR intersect_box_pair_sse2
#define TWINRAY_BOX_PAIR_RAY BoxPairRaySse2
#include "backends/bvh/bvh_traversal.inl"
#undef TWINRAY_BOX_PAIR
#undef TWINRAY_BOX_PAIR_RAY
#undef TWINRAY_KERNEL

struct RecordingObserver {
  std::vector<BvhVisit>* visits;
  void enter(std::uint32_t node, float tmax) const { visits->push_back({node, tmax}); }
};

}  // namespace bvh_trace

bool BvhBackend::intersect_traced(const Ray& ray, Hit& hit, std::vector<BvhVisit>& visits, QueryStats* stats) const {
  using namespace bvh_trace;
  visits.clear();
  if (stats) ++stats->queries;
  hit = Hit{};
  if (!is_valid_ray(ray) || nodes_.empty()) return false;
  const BvhView view{nodes_, &prims_};
  const RecordingObserver observer{&visits};
  const bool triangles = !prims_.triangle_keys.empty(), spheres = !prims_.spheres.empty();
  if (triangles && spheres) return bvh_intersect_observed<true, true>(view, ray, hit, stats, observer);
  if (spheres) return bvh_intersect_observed<false, true>(view, ray, hit, stats, observer);
  return bvh_intersect_observed<true, false>(view, ray, hit, stats, observer);
}

bool BvhBackend::occluded_traced(const Ray& ray, std::vector<BvhVisit>& visits, QueryStats* stats) const {
  using namespace bvh_trace;
  visits.clear();
  if (stats) ++stats->queries;
  if (!is_valid_ray(ray) || nodes_.empty()) return false;
  const BvhView view{nodes_, &prims_};
  const RecordingObserver observer{&visits};
  const bool triangles = !prims_.triangle_keys.empty(), spheres = !prims_.spheres.empty();
  if (triangles && spheres) return bvh_occluded_observed<true, true>(view, ray, stats, observer);
  if (spheres) return bvh_occluded_observed<false, true>(view, ray, stats, observer);
  return bvh_occluded_observed<true, false>(view, ray, stats, observer);
}

}  // namespace twinray
