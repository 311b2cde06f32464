#pragma once
// Ray-sphere intersection that stays accurate for tiny far spheres and huge near ones.
//
// Method: Haines, Günther, Akenine-Möller, "Precision Improvements for Ray/Sphere Intersection",
// Ray Tracing Gems ch. 7. With f = org - center, the quadratic is
//     a t^2 + 2 b t + c = 0,   a = dir.dir,  b = f.dir,  c = f.f - r^2.
// Two cancellations ruin the textbook formula in float:
//  1. The discriminant b^2 - a c subtracts two huge, nearly equal numbers when the sphere is small and far.
//     Instead we use the identity b^2 - a c = a (r^2 - |l|^2), where l = f - (b/a) dir is the vector from
//     the center to the point of closest approach: |l| is of the order of r, so nothing large cancels.
//  2. -b +- sqrt(disc) cancels for the root of the "wrong" sign. We form q = -(b + sign(b) sqrt(disc)),
//     which only ever adds magnitudes, and get the roots as c/q and q/a (Vieta: t0 t1 = c/a).
// Everything is evaluated in double: products of floats are exact in double, so the only remaining
// error is a few double roundings, far below the final rounding of t to float.
//
// Interval convention (the one of core/geometry/ray.h): a root counts when tmin <= t <= tmax, compared
// after rounding t to float, i.e. exactly the t that is reported. The closest qualifying root is
// returned: from outside that is the entry point; from inside (near root < tmin) it is the exit point.
//
// Tangency: when the computed discriminant is exactly zero the two roots coincide and the ray counts as
// hitting (grazing) the sphere once, at that root. A negative discriminant is a miss. NaN inputs (e.g. a
// NaN radius) make every comparison false and therefore miss.

#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace twinray {

namespace sphere_detail {

struct DVec3 {
  double x, y, z;
};
inline DVec3 to_double(const glm::vec3& v) {
  return {static_cast<double>(v.x), static_cast<double>(v.y), static_cast<double>(v.z)};
}
inline double dot(const DVec3& a, const DVec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// Both roots of |org + t dir - center| = radius in double, t0 <= t1. False when the ray misses.
inline bool sphere_roots(const glm::vec3& org, const glm::vec3& dir, const glm::vec3& center, float radius,
                         double& t0, double& t1) {
  const DVec3 d = to_double(dir);
  // org - center is formed in double: the float difference would already lose the tiny sphere.
  const DVec3 f{static_cast<double>(org.x) - center.x, static_cast<double>(org.y) - center.y,
                static_cast<double>(org.z) - center.z};
  const double r = radius;
  const double a = dot(d, d);
  const double b = dot(f, d);
  const double s = b / a;
  const DVec3 l{f.x - s * d.x, f.y - s * d.y, f.z - s * d.z};  // center -> closest approach
  const double disc = a * (r * r - dot(l, l));
  if (!(disc >= 0.0)) return false;  // also rejects NaN
  // c = |f|^2 - r^2 as (|f| - r)(|f| + r): the factor |f| - r keeps its relative accuracy for an origin
  // close to a huge sphere (|f| ~ 1e5, |f| - r ~ 1).
  const double flen = std::sqrt(dot(f, f));
  const double c = (flen - r) * (flen + r);
  const double q = -(b + std::copysign(std::sqrt(disc), b));
  if (q == 0.0) {
    // b == 0 and disc == 0: the origin lies on the sphere and the ray is tangent there (c == 0); the
    // double root is t = 0. c/q would be 0/0.
    t0 = t1 = 0.0;
    return true;
  }
  const double ra = c / q;
  const double rb = q / a;
  t0 = std::min(ra, rb);
  t1 = std::max(ra, rb);
  return true;
}

}  // namespace sphere_detail

// Closest root of |org + t dir - center| = radius with tmin <= t <= tmax. Returns false when none.
inline bool intersect_sphere(const glm::vec3& org, const glm::vec3& dir, const glm::vec3& center, float radius,
                             float tmin, float tmax, float& t_out) {
  double t0 = 0.0, t1 = 0.0;
  if (!sphere_detail::sphere_roots(org, dir, center, radius, t0, t1)) return false;
  const auto near_t = static_cast<float>(t0);
  if (near_t >= tmin && near_t <= tmax) {
    t_out = near_t;
    return true;
  }
  const auto far_t = static_cast<float>(t1);
  if (far_t >= tmin && far_t <= tmax) {
    t_out = far_t;
    return true;
  }
  return false;
}

namespace sphere_detail {

// The unit vector from the center to the hit at float parameter t, in double: the double root that t was
// rounded from is recomputed and the point evaluated from it (see sphere_hit_attributes).
inline DVec3 hit_direction(const glm::vec3& org, const glm::vec3& dir, float t, const glm::vec3& center, float radius) {
  double t0 = 0.0, t1 = 0.0;
  double td = t;
  if (sphere_roots(org, dir, center, radius, t0, t1)) {
    // Mirror intersect_sphere's choice: it reports the near root whenever that root (rounded) qualifies, so
    // a t equal to the rounded near root is the near root. Near tangency both roots may round to within an
    // ulp of each other, which is why "the root nearest to t" would not do. For any other t (a caller's
    // own parameter) the nearest root is used.
    if (static_cast<float>(t0) == t) td = t0;
    else if (static_cast<float>(t1) == t) td = t1;
    else td = std::abs(t0 - td) <= std::abs(t1 - td) ? t0 : t1;
  }
  const DVec3 p{static_cast<double>(org.x) + td * dir.x - center.x,
                static_cast<double>(org.y) + td * dir.y - center.y,
                static_cast<double>(org.z) + td * dir.z - center.z};
  const double len = std::sqrt(dot(p, p));
  if (!(len > 0.0)) return {0.0, 1.0, 0.0};  // only reachable for a zero radius; any unit vector will do
  return {p.x / len, p.y / len, p.z / len};
}

}  // namespace sphere_detail

// The hit point at parameter t, on the sphere to double accuracy and rounded to float once, so its error is
// half an ulp of each of its own coordinates: the premise of the Wächter-Binder spawn offset
// (core/geometry/ray_offset.h). Neither org + t dir nor center + radius * ng in float would do: both carry
// the rounding error of the larger operands (for a ground sphere of radius 1000 centred at y = -1000, about
// 6e-5 in y, far more than the offset), and secondary rays would start inside the sphere: shadow acne.
inline glm::vec3 sphere_hit_point(const glm::vec3& org, const glm::vec3& dir, float t, const glm::vec3& center,
                                  float radius) {
  const sphere_detail::DVec3 n = sphere_detail::hit_direction(org, dir, t, center, radius);
  const double r = radius;
  return glm::vec3(static_cast<float>(center.x + r * n.x), static_cast<float>(center.y + r * n.y),
                   static_cast<float>(center.z + r * n.z));
}

// sphere_hit_point and the normal sphere_hit_attributes gives, from one recomputation of the root: the same
// bits as the two calls, for the renderer, which needs both and no (u, v).
inline void sphere_hit_point_and_normal(const glm::vec3& org, const glm::vec3& dir, float t, const glm::vec3& center,
                                        float radius, glm::vec3& p, glm::vec3& ng) {
  const sphere_detail::DVec3 n = sphere_detail::hit_direction(org, dir, t, center, radius);
  const double r = radius;
  p = glm::vec3(static_cast<float>(center.x + r * n.x), static_cast<float>(center.y + r * n.y),
                static_cast<float>(center.z + r * n.z));
  ng = glm::vec3(static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z));
}

// Unit outward normal and (u,v) = (phi/2pi, theta/pi) (theta from +Y) at parameter t, computed consistently.
//
// A float t cannot locate the hit point on a tiny far sphere (one ulp of t = 1e4 is ~1e-3, the size of the
// sphere), so the point is not taken from org + t dir directly: the double-precision root that t was
// rounded from is recomputed and the point evaluated from it, which puts it on the sphere to double accuracy. The normal is
// then normalize(p - center), never divided by the float radius, so it is unit length to rounding.
// phi = atan2(n.z, n.x) mapped to [0, 2pi), so u is in [0, 1); theta = acos(n.y) in [0, pi].
inline void sphere_hit_attributes(const glm::vec3& org, const glm::vec3& dir, float t, const glm::vec3& center,
                                  float radius, glm::vec3& ng, float& u, float& v) {
  const sphere_detail::DVec3 n = sphere_detail::hit_direction(org, dir, t, center, radius);
  ng = glm::vec3(static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z));

  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  double phi = std::atan2(n.z, n.x);
  if (phi < 0.0) phi += kTwoPi;
  // Rounding may land exactly on 1 (phi just below 2pi): keep the documented half-open range.
  u = std::min(static_cast<float>(phi / kTwoPi), std::nextafter(1.0f, 0.0f));
  v = static_cast<float>(std::acos(std::clamp(n.y, -1.0, 1.0)) / std::numbers::pi);
}

}  // namespace twinray
