#pragma once
// Helpers the ray-query tests share: the non-finite constants, a ray from its four fields, and bitwise
// float and hit equality (for "bit-identical" expectations, where == would let -0 equal +0).

#include "core/geometry/hit.h"
#include "core/geometry/ray.h"

#include <glm/vec3.hpp>

#include <bit>
#include <cstdint>
#include <limits>

namespace twinray::test {

inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

inline Ray make_ray(glm::vec3 org, glm::vec3 dir, float tmin = 0.0f, float tmax = kInf) {
  Ray r;
  r.org = org;
  r.dir = dir;
  r.tmin = tmin;
  r.tmax = tmax;
  return r;
}

inline bool same_bits(float a, float b) { return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b); }

// Two answers the same to the bit: geometry, primitive, t, u, v and the normal.
inline bool same_hit_bits(const Hit& a, const Hit& b) {
  return a.geom_id == b.geom_id && a.prim_id == b.prim_id && same_bits(a.t, b.t) && same_bits(a.u, b.u) &&
         same_bits(a.v, b.v) && same_bits(a.ng.x, b.ng.x) && same_bits(a.ng.y, b.ng.y) && same_bits(a.ng.z, b.ng.z);
}

}  // namespace twinray::test
