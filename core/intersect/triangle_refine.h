#pragma once
// Correctly rounded t, u, v for a triangle that the watertight edge test has accepted.
//
// Why: Woop's test computes t as the barycentric-weighted sum of sheared z coordinates over the
// determinant. For a long thin triangle seen at a grazing angle the edge functions are products near
// cancellation whose absolute error, relative to the small determinant, grows with the aspect ratio: a ray
// of the Sponza atrium at cos = -0.0034 on a 500:1 moulding strip came out 6.3% short (issue 11). The edge
// test itself is exact in sign for its sheared coordinates and stays the hit decision; only the reported
// numbers are recomputed here, from the plane formulas
//     a = p0 - o, e1 = p1 - p0, e2 = p2 - p0, n = e1 x e2, den = d.n
//     t = a.n / den,   u = e2.(a x d) / den,   v = -e1.(a x d) / den      (u weights p1, v weights p2)
// (a x d is evaluated as (a - t d) x d, see certify_barycentrics)
// in double, with a rigorous a-posteriori error bound, and rounded to float only when the bound proves
// which float the exact value rounds to. Otherwise (the exact value lies within the bound of a rounding
// boundary, den's sign is uncertain, or the result leaves float's normal range) the exact GMP/MPFR path
// core/exact/exact_triangle.h decides. Result:
//   t is the exact t of the line's crossing with the triangle's plane, correctly rounded to float (round to
//   nearest, ties to even); u and v the exact barycentrics of that point, clamped to [0, 1], correctly
//   rounded. The clamp only acts when the float edge decision and the exact one disagree at an edge (the
//   sheared coordinates are rounded), where an exact barycentric can be slightly negative.
//   If the line is exactly parallel to the plane (den = 0) there is no crossing: not a hit, although the
//   float determinant was non-zero. A t that rounds to infinity is not a hit either.
// Everything is deterministic, so every caller (the scalar test, the SSE block test, any leaf test) gets
// bit-identical answers from the same inputs.
//
// Error bound. Every input is a float, exact in double. den = sum_i d_i (e1_j e2_k - e1_k e2_j) is a sum of
// products in which each elementary term d_i e1_j e2_k passes through at most 7 roundings (two input
// differences, a product, a difference, a product, two additions), a.n through 8 (the difference a_i).
// By the standard model |fl(x op y) - x op y| <= u |x op y|, u = 2^-53, such a computed sum differs from the
// exact one by at most gamma_8 P, gamma_8 = 8u / (1 - 8u), where P is the same sum over the absolute values
// of the exact terms (Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed., ch. 3). P is
// evaluated from the computed products, which are within a few roundings of the exact ones, so
// P <= P^ (1 + 9u); 10u P^ covers gamma_8 P with room for the rounding of 10u P^ itself. For a quotient
// n/d with |n^ - n| <= En, |d^ - d| <= Ed < |d^|:
//     |n/d - n^/d^| <= (|n^| Ed + |d^| En) / ((|d^| - Ed) |d^|),
// and computing n^ * fl(1/d^) instead of n^/d^ adds at most 3u |q| (one reciprocal shared by t, u and v);
// with |d^| > 2 Ed, 1 / ((|d^| - Ed) |d^|) <= r^2 (1 + 2 Ed |r|) needs no second division; the whole bound
// is scaled by 1 + 2^-40 for the few roundings of its own evaluation. No intermediate
// can underflow or overflow: every non-zero difference of floats is at least 2^-149 and at most 2^129, so
// every non-zero product of three lies in [2^-447, 2^390], far inside double's normal range, which also
// makes flush-to-zero irrelevant here. (Denormals-are-zero, set by the renderer and the harness, reads
// subnormal *float inputs* as 0 in the float test and in this double path alike; the guarantee is then for
// those inputs.)
//
// Cost (docs/bvh-backend.md): refine_triangle_t rejects a candidate outside [tmin, tmax] after the t estimate
// and its bound (the triangle a secondary ray starts from, crossings beyond the closest hit so far) and
// certifies the t of one inside; refine_triangle_uv certifies the barycentrics, which a closest-hit traversal
// asks for once, for the winner. The exact path is rare: ties and near-ties of the rounding, a barycentric of
// exactly 0 (a ray through an edge), extreme slivers at extreme angles; none in 10 000 rays of each kind on
// the dragon and Sponza (refine_detail::exact_fallbacks counts it).

#include "core/exact/exact_triangle.h"

#include <glm/vec3.hpp>

#include <atomic>
#include <cmath>
#include <cstdint>

namespace twinray {

namespace refine_detail {

inline constexpr double kUnit = 0x1p-53;
// The bound constant for the sums of products above: 10u P^ (see the header comment).
inline constexpr double kSumBound = 10.0 * kUnit;

// Plain comparisons rather than std::fmax, which is a library call unless the compiler may assume no NaN.
inline double max2(double a, double b) { return a > b ? a : b; }
inline double max_abs(const glm::dvec3& v) { return max2(std::fabs(v.x), max2(std::fabs(v.y), std::fabs(v.z))); }
inline double sum_abs(const glm::dvec3& v) { return std::fabs(v.x) + std::fabs(v.y) + std::fabs(v.z); }
inline double dot(const glm::dvec3& a, const glm::dvec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline glm::dvec3 cross(const glm::dvec3& a, const glm::dvec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
// a x b and, per component, |a_j b_k| + |a_k b_j| (the absolute terms of the bound).
inline glm::dvec3 cross_with_terms(const glm::dvec3& a, const glm::dvec3& b, glm::dvec3& terms) {
  const double p[6] = {a.y * b.z, a.z * b.y, a.z * b.x, a.x * b.z, a.x * b.y, a.y * b.x};
  terms = {std::fabs(p[0]) + std::fabs(p[1]), std::fabs(p[2]) + std::fabs(p[3]), std::fabs(p[4]) + std::fabs(p[5])};
  return {p[0] - p[1], p[2] - p[3], p[4] - p[5]};
}
inline double abs_dot(const glm::dvec3& a, const glm::dvec3& b) {
  return std::fabs(a.x) * b.x + std::fabs(a.y) * b.y + std::fabs(a.z) * b.z;
}

// What the bounds of numerator and denominator give for every quotient n^ * r with r = fl(1/d^):
// |n/d - n^ r| <= (|n^| Ed + |d^| En) w + 3u |n^ r|, scaled for its own rounding (see the header).
struct Quotient {
  glm::dvec3 n{0.0}, n_terms{0.0};  // the normal e1 x e2 and its absolute terms
  double r = 0.0;        // fl(1 / den)
  double w = 0.0;        // at least 1 / ((|den| - Ed) |den|) up to a few roundings: r^2 (1 + 2 Ed |r|)
  double abs_den = 0.0;
  double den_err = 0.0;
  double error(double num, double num_err, double q) const {
    return ((std::fabs(num) * den_err + abs_den * num_err) * w + 3.0 * kUnit * std::fabs(q)) * (1.0 + 0x1p-40);
  }
};

// den = d.n with its bound; false when its sign is not certain (or Ed |r| > 1/2, where the cheap w would not
// bound the exact one). 1 / (1 - x) <= 1 + 2x for 0 <= x <= 1/2 gives w without a second division.
inline bool crossing_denominator(const glm::dvec3& d, const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                                 Quotient& q) {
  q.n = cross_with_terms(p1 - p0, p2 - p0, q.n_terms);
  const double den = dot(d, q.n);
  q.den_err = kSumBound * abs_dot(d, q.n_terms);
  q.abs_den = std::fabs(den);
  if (!(q.abs_den > 2.0 * q.den_err)) return false;
  q.r = 1.0 / den;
  q.w = q.r * q.r * (1.0 + 2.0 * q.den_err * std::fabs(q.r));
  return true;
}

// The floats that the ends of [x - err, x + err] round to, the ends widened past their own rounding: every
// real in the interval rounds to a float between lo and hi, since rounding is monotonic. lo == hi certifies
// the rounding of the exact value. Flush-to-zero can turn an end in the subnormal range into a zero, which
// keeps the order (it rounds toward zero), so comparisons against the normal floats tmin, tmax stay valid;
// only a *certified value* must be normal (see certified()).
struct Ends {
  float lo, hi;
  bool certified() const { return lo == hi && std::fabs(lo) >= 0x1p-125f && std::fabs(lo) <= 0x1.fffffep127f; }
};
inline Ends round_ends(double x, double err) {
  const double slack = err + std::fabs(x) * 0x1p-52;  // covers the rounding of x - slack and x + slack
  return {static_cast<float>(x - slack), static_cast<float>(x + slack)};
}

// q (within err of the exact value) clamped to [0, 1], if certain: 0 and 1 are floats, so clamping after
// rounding is the same as rounding after clamping. Values that round into the subnormal range go to the
// exact path, except when the whole interval lies at or below 0 (then 0) or at or above 1 (then 1).
inline bool certify_barycentric(double q, double err, float& out) {
  const double slack = err + std::fabs(q) * 0x1p-52;  // as in round_ends
  const double lo = q - slack, hi = q + slack;
  if (hi <= 0.0) {
    out = 0.0f;
    return true;
  }
  if (lo >= 1.0) {
    out = 1.0f;
    return true;
  }
  const float flo = static_cast<float>(lo), fhi = static_cast<float>(hi);
  const float clo = flo < 0.0f ? 0.0f : (flo > 1.0f ? 1.0f : flo);
  const float chi = fhi < 0.0f ? 0.0f : (fhi > 1.0f ? 1.0f : fhi);
  if (clo != chi || !(clo >= 0x1p-125f)) return false;
  out = clo;
  return true;
}

// u = e2.(a x d) / den and v = -e1.(a x d) / den, certified as above. a x d is computed as h x d with
// h = a - t d, the vector from p0 to the crossing (the same cross product, since t d x d = 0): for a ray whose
// a is nearly parallel to d (every ray that meets a small triangle far away) a x d itself cancels to a few
// digits, h x d does not. h is formed without losing a: t d_k is exact (a product of two floats), the
// rounding error of a_k = p0_k - o_k is recovered exactly by TwoSum (Knuth) and added back, so each h_k is
// within 2u |h_k| + u^2 |a_k| of its exact value; with the remaining roundings (a product, a difference, a
// product, two additions and e's own) each term passes through at most 8, and the u^2 |a| part adds at most
// 2^-100 |e|_1 max|a| max|d|.
inline bool certify_barycentrics(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& p0, const glm::dvec3& e1,
                                 const glm::dvec3& e2, float t, const Quotient& quotient, float& u, float& v) {
  const double td = static_cast<double>(t);
  glm::dvec3 h;
  double max_a = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double a_k = p0[k] - o[k];
    const double back = a_k - p0[k];  // TwoSum of p0_k and -o_k: a_k + error is exactly p0_k - o_k
    const double error = (p0[k] - (a_k - back)) + (-o[k] - back);
    h[k] = (a_k - td * d[k]) + error;
    max_a = max2(max_a, std::fabs(a_k));
  }
  glm::dvec3 terms;
  const glm::dvec3 q = cross_with_terms(h, d, terms);
  const double tiny = 0x1p-100 * max_a * max_abs(d);
  const double u_num = dot(e2, q), v_num = -dot(e1, q);
  const double u_err = kSumBound * abs_dot(e2, terms) + tiny * sum_abs(e2);
  const double v_err = kSumBound * abs_dot(e1, terms) + tiny * sum_abs(e1);
  const double qu = u_num * quotient.r, qv = v_num * quotient.r;
  return certify_barycentric(qu, quotient.error(u_num, u_err, qu), u) &&
         certify_barycentric(qv, quotient.error(v_num, v_err, qv), v);
}

// How many times the exact path was taken, process-wide (for tests and measurements of the fallback rate).
inline std::atomic<std::uint64_t> exact_fallbacks{0};

// The exact path (GMP / MPFR): t, u, v of the crossing, or false when there is none (den == 0 or t rounds to
// infinity). Out of line and cold.
[[gnu::cold, gnu::noinline]] inline bool exact_crossing(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& p0,
                                                        const glm::dvec3& p1, const glm::dvec3& p2, float& t, float& u,
                                                        float& v) {
  exact_fallbacks.fetch_add(1, std::memory_order_relaxed);
  if (!exact::triangle_crossing_attributes({o, d, p0, p1, p2}, t, u, v)) return false;
  return std::isfinite(t);
}

}  // namespace refine_detail

// The crossing parameter of the line o + t d with triangle (p0, p1, p2), which the caller's edge test has
// accepted: false when there is no crossing (see above) or its correctly rounded t lies outside
// [tmin, tmax]; otherwise the correctly rounded t. Inputs are doubles holding floats.
inline bool refine_triangle_t(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& p0, const glm::dvec3& p1,
                              const glm::dvec3& p2, float tmin, float tmax, float& t_out) {
  using namespace refine_detail;
  const glm::dvec3 a = p0 - o;
  Quotient quotient;
  const bool den_certain = crossing_denominator(d, p0, p1, p2, quotient);
  float t = 0.0f;
  bool certain = false;
  if (den_certain) {
    const double num = dot(a, quotient.n);
    const double num_err = kSumBound * abs_dot(a, quotient.n_terms);
    const double q = num * quotient.r;
    const Ends ends = round_ends(q, quotient.error(num, num_err, q));
    // Certainly outside: every t within the bound rounds below tmin or above tmax. (Most rejected
    // candidates end here: the triangle a secondary ray starts from, crossings beyond the closest hit.)
    if (ends.hi < tmin || ends.lo > tmax) return false;
    certain = ends.certified();
    t = ends.lo;
  }
  if (!certain) {
    float u, v;
    if (!exact_crossing(o, d, p0, p1, p2, t, u, v)) return false;
  }
  if (!(t >= tmin && t <= tmax)) return false;
  t_out = t;
  return true;
}

// The barycentrics (u weights p1, v weights p2) of that crossing, correctly rounded after clamping to
// [0, 1]; `t` is what refine_triangle_t returned for the same inputs. Kept apart so that a closest-hit
// traversal computes them once, for the winner.
inline void refine_triangle_uv(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& p0, const glm::dvec3& p1,
                               const glm::dvec3& p2, float t, float& u, float& v) {
  using namespace refine_detail;
  Quotient quotient;
  if (crossing_denominator(d, p0, p1, p2, quotient) &&
      certify_barycentrics(o, d, p0, p1 - p0, p2 - p0, t, quotient, u, v))
    return;
  float t_exact;
  exact_crossing(o, d, p0, p1, p2, t_exact, u, v);
}

// Both: what a leaf test reports for a candidate its edge test accepted.
inline bool refine_triangle_hit(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& p0, const glm::dvec3& p1,
                                const glm::dvec3& p2, float tmin, float tmax, float& t, float& u, float& v) {
  if (!refine_triangle_t(o, d, p0, p1, p2, tmin, tmax, t)) return false;
  refine_triangle_uv(o, d, p0, p1, p2, t, u, v);
  return true;
}

}  // namespace twinray
