#pragma once
// Axis-aligned bounding box. An empty box has lo = +inf, hi = -inf so that extend() needs no branch.

#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace twinray {

struct Bounds3 {
  glm::vec3 lo{std::numeric_limits<float>::infinity()};
  glm::vec3 hi{-std::numeric_limits<float>::infinity()};

  static Bounds3 of_point(const glm::vec3& p) { return {p, p}; }

  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  void extend(const glm::vec3& p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
  void extend(const Bounds3& b) { lo = glm::min(lo, b.lo); hi = glm::max(hi, b.hi); }
  glm::vec3 extent() const { return empty() ? glm::vec3(0.0f) : hi - lo; }
  // Halves first: the same float as 0.5 (lo + hi) (halving commutes with rounding), without overflowing for a
  // box near float's largest values.
  glm::vec3 center() const { return 0.5f * lo + 0.5f * hi; }
  // In double, then rounded (at most float's largest finite value): a float sum of squares overflows for boxes
  // beyond about 1e19 and underflows to 0 below about 1e-19.
  float diagonal() const {
    if (empty()) return 0.0f;
    const glm::dvec3 e = glm::dvec3(hi) - glm::dvec3(lo);
    const double d = std::sqrt(e.x * e.x + e.y * e.y + e.z * e.z);
    return static_cast<float>(std::min(d, double(std::numeric_limits<float>::max())));
  }
  // Half the surface area: the SAH only ever uses ratios, so the factor 2 is dropped.
  float half_area() const {
    if (empty()) return 0.0f;
    const glm::vec3 e = hi - lo;
    return e.x * e.y + e.y * e.z + e.z * e.x;
  }
  int largest_axis() const {
    const glm::vec3 e = extent();
    return (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
  }
  bool contains(const Bounds3& b) const {
    return b.lo.x >= lo.x && b.lo.y >= lo.y && b.lo.z >= lo.z && b.hi.x <= hi.x && b.hi.y <= hi.y && b.hi.z <= hi.z;
  }
};

inline Bounds3 merge(Bounds3 a, const Bounds3& b) { a.extend(b); return a; }

}  // namespace twinray
