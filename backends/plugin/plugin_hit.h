#pragma once
// Conversions between twinray's rays and hits and the plain C structs of the plugin ABI, and the one check
// twinray makes on a plugin's answer. Shared by the in-process and the isolated plugin backends, so both
// treat a plugin's answers identically.

#include "backends/plugin/twinray_plugin.h"
#include "core/geometry/hit.h"
#include "core/geometry/ray.h"
#include "core/geometry/scene_geometry.h"

#include <cstdint>
#include <string>
#include <vector>

namespace twinray {

static_assert(sizeof(twinray_id) == sizeof(std::uint32_t), "ids cross the ABI as 32-bit unsigned integers");
static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "mesh positions are passed as packed float triples");
static_assert(sizeof(glm::uvec3) == 3 * sizeof(twinray_id), "mesh indices are passed as packed id triples");

inline twinray_ray to_plugin_ray(const Ray& r) {
  twinray_ray p;
  p.org[0] = r.org.x;
  p.org[1] = r.org.y;
  p.org[2] = r.org.z;
  p.tmin = r.tmin;
  p.dir[0] = r.dir.x;
  p.dir[1] = r.dir.y;
  p.dir[2] = r.dir.z;
  p.tmax = r.tmax;
  return p;
}

inline twinray_sphere to_plugin_sphere(const Sphere& s) {
  twinray_sphere p;
  p.geom_id = s.geom_id;
  p.center[0] = s.center.x;
  p.center[1] = s.center.y;
  p.center[2] = s.center.z;
  p.radius = s.radius;
  return p;
}

inline twinray_hit plugin_miss() {
  twinray_hit h{};
  h.geom_id = TWINRAY_INVALID_ID;
  h.prim_id = TWINRAY_INVALID_ID;
  return h;
}

// Which primitives exist, by geometry id: the check of every hit a plugin reports.
class PrimitiveIndex {
 public:
  PrimitiveIndex() = default;
  explicit PrimitiveIndex(const SceneGeometry& geometry) : count_by_geom_(geometry.geom_id_end(), 0) {
    for (const TriangleMesh& m : geometry.meshes) count_by_geom_[m.geom_id] = static_cast<std::uint32_t>(m.indices.size());
    for (const Sphere& s : geometry.spheres) count_by_geom_[s.geom_id] = 1;
  }

  bool exists(std::uint32_t geom_id, std::uint32_t prim_id) const {
    return geom_id < count_by_geom_.size() && prim_id < count_by_geom_[geom_id];
  }

 private:
  std::vector<std::uint32_t> count_by_geom_;  // 0 for ids that are not in the scene
};

// A hit naming a geometry or primitive that does not exist would make the renderer index out of bounds, so
// it is a contract violation rather than a wrong answer for the crosscheck to report. Everything else (t
// outside [tmin, tmax], NaN, a wrong normal) is passed through for the comparison to judge.
inline std::string nonexistent_primitive_message(const std::string& backend_name, const twinray_hit& h) {
  return backend_name + ": reported a hit on geom_id " + std::to_string(h.geom_id) + ", prim_id " +
         std::to_string(h.prim_id) + ", which the scene does not have";
}

inline Hit from_plugin_hit(const twinray_hit& h) {
  Hit hit;
  hit.t = h.t;
  hit.u = h.u;
  hit.v = h.v;
  hit.geom_id = h.geom_id;
  hit.prim_id = h.prim_id;
  hit.ng = glm::vec3(h.ng[0], h.ng[1], h.ng[2]);
  return hit;
}

}  // namespace twinray
