#pragma once
// The result of a closest-hit query, identical in layout for every backend.

#include <glm/vec3.hpp>

#include <cstdint>
#include <limits>

namespace twinray {

inline constexpr std::uint32_t kInvalidId = 0xFFFFFFFFu;

struct Hit {
  float t = std::numeric_limits<float>::infinity();
  // Barycentrics: the hit point is (1-u-v)*p0 + u*p1 + v*p2 for triangles.
  // For spheres u = phi/(2 pi) in [0,1), v = theta/pi in [0,1] with theta measured from +Y.
  float u = 0.0f;
  float v = 0.0f;
  std::uint32_t geom_id = kInvalidId;
  std::uint32_t prim_id = kInvalidId;
  // Unit geometric normal. Triangles: normalize(cross(p1-p0, p2-p0)) (the counter-clockwise front).
  // Spheres: outward. Never flipped toward the ray.
  glm::vec3 ng{0.0f};

  bool found() const { return geom_id != kInvalidId; }
};

// The total order used to break ties between equidistant hits: smaller t first, then the lower
// (geom_id, prim_id). Backends that can honour it use exactly this predicate, so results do not depend on
// traversal order.
inline bool precedes(float t, std::uint32_t geom_id, std::uint32_t prim_id, const Hit& h) {
  if (t != h.t) return t < h.t;
  if (geom_id != h.geom_id) return geom_id < h.geom_id;
  return prim_id < h.prim_id;
}

}  // namespace twinray
