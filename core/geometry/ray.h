#pragma once
// A ray and its parametric interval.
//
// Interval convention (every backend honours it): a hit at parameter t counts when
//     tmin <= t <= tmax            (closed at both ends)
// The direction need not be unit length; t is measured in units of |dir|.
// A ray is *valid* when origin and direction are finite, the direction is not the zero vector,
// 0 <= tmin <= tmax and neither bound is NaN (tmax may be +inf). Invalid rays are reported as misses
// by every backend (Embree would abort the process on some of them, see backends/embree).

#include <glm/vec3.hpp>
#include <glm/geometric.hpp>

#include <cmath>
#include <limits>

namespace twinray {

struct Ray {
  glm::vec3 org{0.0f};
  float tmin = 0.0f;
  glm::vec3 dir{0.0f, 0.0f, -1.0f};
  float tmax = std::numeric_limits<float>::infinity();

  glm::vec3 at(float t) const { return org + t * dir; }
};
static_assert(sizeof(Ray) == 32, "Ray is a 32-byte POD so batches stay cache friendly");

inline bool is_valid_ray(const Ray& r) {
  const bool finite = std::isfinite(r.org.x) && std::isfinite(r.org.y) && std::isfinite(r.org.z) &&
                      std::isfinite(r.dir.x) && std::isfinite(r.dir.y) && std::isfinite(r.dir.z);
  const bool nonzero = r.dir.x != 0.0f || r.dir.y != 0.0f || r.dir.z != 0.0f;
  // Written so that NaN bounds fail the comparisons.
  const bool interval = r.tmin >= 0.0f && r.tmin <= r.tmax && std::isfinite(r.tmin);
  return finite && nonzero && interval;
}

}  // namespace twinray
