#pragma once
// The backend interface: the one seam between the renderer and every intersection engine.
//
// core/ defines it and knows no implementation; backends/ implements it and knows no integrator.
// A backend is built once from a SceneGeometry (which must outlive it) and is then immutable: all query
// functions are const and safe to call from many threads at once. Statistics are accumulated into a
// caller-owned QueryStats, so each thread keeps its own and nothing is shared on the hot path.
//
// One virtual call per ray (or per batch), never per primitive test.

#include "core/geometry/hit.h"
#include "core/geometry/ray.h"
#include "core/geometry/scene_geometry.h"

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace twinray {

// Traversal cost of queries, for backends that can count it (BackendTraits::counts_traversal).
struct QueryStats {
  std::uint64_t queries = 0;
  std::uint64_t nodes_visited = 0;     // interior and leaf nodes whose box was tested
  std::uint64_t primitives_tested = 0; // ray-primitive intersection tests

  QueryStats& operator+=(const QueryStats& o) {
    queries += o.queries;
    nodes_visited += o.nodes_visited;
    primitives_tested += o.primitives_tested;
    return *this;
  }
};

// What a backend built, and what it cost. Tree figures are zero for backends without an accessible tree.
struct BuildStats {
  double build_seconds = 0.0;
  std::size_t memory_bytes = 0;   // acceleration structure and private copies of geometry
  std::size_t triangles = 0;
  std::size_t spheres = 0;
  bool built_triangles = false;   // false: the scene has none, so no triangle geometry was created
  bool built_spheres = false;     // false: the scene has none, so no sphere geometry was created
  // Tree statistics (bvh backend).
  std::size_t nodes = 0;
  std::size_t leaves = 0;
  std::size_t max_depth = 0;
  double sah_cost = 0.0;          // with the builder's own traversal and intersection costs
};

struct BackendTraits {
  bool counts_traversal = false;  // fills QueryStats::nodes_visited / primitives_tested
  bool honours_ties = false;      // equal t resolved by the lower (geom_id, prim_id), see hit.h
  bool watertight = false;        // no ray lost through shared edges and vertices of closed meshes
};

class Backend {
 public:
  virtual ~Backend() = default;
  Backend(const Backend&) = delete;
  Backend& operator=(const Backend&) = delete;

  virtual std::string_view name() const = 0;
  virtual BackendTraits traits() const = 0;

  // Builds the acceleration structure. Called once, before any query.
  virtual void build(const SceneGeometry& geometry) = 0;
  virtual BuildStats build_stats() const = 0;

  // Closest hit in [ray.tmin, ray.tmax]. Returns hit.found(); `hit` is reset to a miss otherwise.
  virtual bool intersect(const Ray& ray, Hit& hit, QueryStats* stats = nullptr) const = 0;
  // Any hit in [ray.tmin, ray.tmax].
  virtual bool occluded(const Ray& ray, QueryStats* stats = nullptr) const = 0;

  // The closest hit's t, geom_id and prim_id only: the same answer as intersect() for those three, while
  // hit.u, hit.v and hit.ng are unspecified (a backend may fill them or not). For callers that look the
  // surface up themselves: the renderer reads its own per-triangle table (core/render/triangle_surface.h),
  // which saves the backend certifying barycentrics and normalising a normal nobody reads. The default
  // calls intersect(); a backend overrides it when it can skip the attributes.
  virtual bool intersect_ids(const Ray& ray, Hit& hit, QueryStats* stats = nullptr) const {
    return intersect(ray, hit, stats);
  }

  // Batches. The defaults loop over the single-ray calls; a backend overrides them when it has a faster
  // path. hits.size() and occluded.size() must equal rays.size().
  virtual void intersect(std::span<const Ray> rays, std::span<Hit> hits, QueryStats* stats = nullptr) const;
  virtual void occluded(std::span<const Ray> rays, std::span<std::uint8_t> occluded,
                        QueryStats* stats = nullptr) const;

 protected:
  Backend() = default;
};

}  // namespace twinray
