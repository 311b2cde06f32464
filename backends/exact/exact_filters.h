#pragma once
// Certain answers in double precision, so that the exact backend reaches GMP only for primitives the ray
// passes within rounding error of.
//
// Every input is a float held exactly in a double. The triangle filter computes the three barycentric
// numerators e0 = d.(b x c), e1 = d.(c x a), e2 = d.(a x b) (a, b, c = vertices - origin) in double; each
// elementary term passes through at most 6 roundings (two differences, a product, a difference, a product,
// two additions), so each computed e_i is within gamma_6 P_i of the exact one, P_i the sum of the absolute
// terms, bounded by 2 |d|_1 max|b| max|c| (and cyclically); 10u P_i (triangle_refine.h's constant, made for
// up to 8 roundings) covers that with room for the bound's own rounding. Two numerators certainly of opposite signs: the line
// misses the closed triangle. All three certainly of one sign: it crosses the interior (no fill rule, and
// den = e0 + e1 + e2 is non-zero). Anything else goes to the exact test. No product underflows (every
// non-zero difference of floats is at least 2^-149), so flush-to-zero cannot interfere.
//
// The sphere filter only proves misses: the distance |l| from the center to the line, l = f - (f.d / d.d) d,
// has an absolute error far below 2^-28 max|f| (a few dozen roundings of relative size 2^-53, each on a
// quantity at most |f|), so |l| > r + 2^-28 (4 max|f| + r) is a certain miss.

#include "core/intersect/triangle_refine.h"

#include <glm/vec3.hpp>

#include <cmath>

namespace twinray::exact_filter {

enum class Decision { Miss, Hit, Undecided };

inline Decision triangle(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& p0, const glm::dvec3& p1,
                         const glm::dvec3& p2) {
  using refine_detail::cross;
  using refine_detail::dot;
  using refine_detail::kSumBound;
  using refine_detail::max_abs;
  using refine_detail::sum_abs;
  const glm::dvec3 a = p0 - o, b = p1 - o, c = p2 - o;
  const double ma = max_abs(a), mb = max_abs(b), mc = max_abs(c);
  const double scale = 2.0 * kSumBound * sum_abs(d);
  const double e[3] = {dot(d, cross(b, c)), dot(d, cross(c, a)), dot(d, cross(a, b))};
  const double err[3] = {scale * mb * mc, scale * mc * ma, scale * ma * mb};
  bool certain_positive = false, certain_negative = false, all_certain = true;
  for (int i = 0; i < 3; ++i) {
    certain_positive = certain_positive || e[i] > err[i];
    certain_negative = certain_negative || e[i] < -err[i];
    all_certain = all_certain && std::fabs(e[i]) > err[i];
  }
  if (certain_positive && certain_negative) return Decision::Miss;
  return all_certain ? Decision::Hit : Decision::Undecided;
}

inline bool sphere_certainly_missed(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& center, double radius) {
  const glm::dvec3 f = o - center;
  const double s = (f.x * d.x + f.y * d.y + f.z * d.z) / (d.x * d.x + d.y * d.y + d.z * d.z);
  const glm::dvec3 l = f - s * d;
  const double distance = std::sqrt(l.x * l.x + l.y * l.y + l.z * l.z);
  const double largest = std::fmax(std::fabs(f.x), std::fmax(std::fabs(f.y), std::fabs(f.z)));
  return distance > radius + 0x1p-28 * (4.0 * largest + radius);
}

}  // namespace twinray::exact_filter
