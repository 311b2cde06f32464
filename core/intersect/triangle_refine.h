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
// and computing n^ * fl(1/d^) instead of n^/d^ adds at most 3u |q| (one reciprocal shared by u and v; t is
// divided directly and its bound computed by a second division beside it, see t_ends);
// with |d^| > 2 Ed, 1 / ((|d^| - Ed) |d^|) <= r^2 (1 + 2 Ed |r|) needs no second division; the whole bound
// is scaled by 1 + 2^-40 for the few roundings of its own evaluation. No intermediate
// can underflow or overflow: every non-zero difference of floats is at least 2^-149 and at most 2^129, so
// every non-zero product of three lies in [2^-447, 2^390], far inside double's normal range, which also
// makes flush-to-zero irrelevant here. (Denormals-are-zero, set by the renderer and the harness, reads
// subnormal *float inputs* as 0 in the float test and in this double path alike; the guarantee is then for
// those inputs.)
//
// Evaluation. The three coordinates of a vector sit in one SIMD vector (x, y, z, 0), so a difference, a
// product or an absolute value of three components is one vector operation, a cross product two products and
// a difference of permuted vectors, and the four sums a t needs (den, num and the absolute sums of their
// bounds) come out of one transposing reduction. The fourth lane stays exactly 0 through every operation
// (0 - 0, 0 * x, |0|), so it adds nothing to a sum. The operations are the same IEEE operations as in scalar
// code; only the order of the three-term additions differs, and each term still passes through at most two
// of them, which is what the bound counts. (GCC's generic vectors: one AVX instruction per operation in the
// AVX2 and AVX-512 kernels, two SSE2 instructions elsewhere.)
//
// Cost (docs/bvh-backend.md): refine_triangle_t rejects a candidate outside [tmin, tmax] after the t estimate
// and its bound (the triangle a secondary ray starts from, crossings beyond the closest hit so far) and
// certifies the t of one inside; refine_triangle_uv certifies the barycentrics, which a closest-hit traversal
// asks for once, for the winner, from the crossing its t test left (refine_uv_kept: the traversal keeps the
// best candidate's Crossing instead of computing it again); refine_triangle_in_interval only decides
// membership, for any-hit queries. Certifying t as each candidate is found, rather than lazily for the winner
// alone, costs next to nothing: the certificate (both ends of the interval rounding to one float) is a few
// instructions, and the interval it reads is what rejecting a candidate or shrinking tmax needs anyway.
// The exact path is rare: ties and near-ties of the rounding, a barycentric of exactly 0 (a ray through an
// edge), extreme slivers at extreme angles; none in 10 000 rays of each kind on the dragon and Sponza
// (refine_detail::exact_fallbacks counts it).

#include "core/exact/exact_triangle.h"

#include <glm/vec3.hpp>

#include <atomic>
#include <cmath>
#include <cstdint>

namespace twinray {

namespace refine_detail {

using Vec2d = double __attribute__((vector_size(16)));
using Vec2u = std::uint64_t __attribute__((vector_size(16)));
using Vec4d = double __attribute__((vector_size(32)));
using Vec4u = std::uint64_t __attribute__((vector_size(32)));

inline constexpr double kUnit = 0x1p-53;
// The bound constant for the sums of products above: 10u P^ (see the header comment).
inline constexpr double kSumBound = 10.0 * kUnit;
// The same scaled by 1 + 2^-40 (exact: 44 significant bits), for the bounds of den and a.n: a larger bound is
// still a bound, and the 2^-40 carried in them covers the few roundings of t's bound (t_ends), which then
// needs no product of its own on the candidate's dependency chain.
inline constexpr double kCrossingBound = kSumBound * (1.0 + 0x1p-40);

// Scalar helpers (the exact backend's filters, backends/exact/exact_filters.h, share them). Plain comparisons
// rather than std::fmax, which is a library call unless the compiler may assume no NaN.
inline double max2(double a, double b) { return a > b ? a : b; }
inline double max_abs(const glm::dvec3& v) { return max2(std::fabs(v.x), max2(std::fabs(v.y), std::fabs(v.z))); }
inline double sum_abs(const glm::dvec3& v) { return std::fabs(v.x) + std::fabs(v.y) + std::fabs(v.z); }
inline double dot(const glm::dvec3& a, const glm::dvec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline glm::dvec3 cross(const glm::dvec3& a, const glm::dvec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// Every helper below is always inlined, so that the vector code is compiled for the instruction set of the
// leaf test that uses it (the kernels choose theirs by target attributes).
#define TWINRAY_REFINE_INLINE [[gnu::always_inline]] inline

// (x, y, z, 0) in a GCC / Clang generic vector (see "Evaluation" above). Wrapped in a struct because a
// function returning a bare 32-byte vector has another ABI with AVX than without (GCC warns, -Wpsabi),
// while a 32-byte struct is returned in memory either way (and, inlined, never is).
struct Vec4 {
  Vec4d v;
};
TWINRAY_REFINE_INLINE Vec4 operator+(const Vec4& a, const Vec4& b) { return {a.v + b.v}; }
TWINRAY_REFINE_INLINE Vec4 operator-(const Vec4& a, const Vec4& b) { return {a.v - b.v}; }
TWINRAY_REFINE_INLINE Vec4 operator*(const Vec4& a, const Vec4& b) { return {a.v * b.v}; }
TWINRAY_REFINE_INLINE Vec4 operator*(double s, const Vec4& a) { return {s * a.v}; }
TWINRAY_REFINE_INLINE Vec4 operator-(const Vec4& a) { return {-a.v}; }

// Three scalar conversions: from a vertex scattered over a structure-of-arrays block, GCC assembles them with
// fewer instructions than a float vector converted at once.
TWINRAY_REFINE_INLINE Vec4 load(const glm::vec3& p) {
  return {Vec4d{static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z), 0.0}};
}
TWINRAY_REFINE_INLINE Vec4 load(const glm::dvec3& p) { return {Vec4d{p.x, p.y, p.z, 0.0}}; }
TWINRAY_REFINE_INLINE glm::dvec3 store(const Vec4& a) { return {a.v[0], a.v[1], a.v[2]}; }

TWINRAY_REFINE_INLINE Vec4 abs(const Vec4& a) {
  constexpr std::uint64_t kMagnitude = ~std::uint64_t{0} >> 1;
  return {reinterpret_cast<Vec4d>(reinterpret_cast<Vec4u>(a.v) & Vec4u{kMagnitude, kMagnitude, kMagnitude, kMagnitude})};
}
TWINRAY_REFINE_INLINE Vec2d abs(const Vec2d& v) {
  constexpr std::uint64_t kMagnitude = ~std::uint64_t{0} >> 1;
  return reinterpret_cast<Vec2d>(reinterpret_cast<Vec2u>(v) & Vec2u{kMagnitude, kMagnitude});
}
// (y, z, x) and (z, x, y): a x b = yzx(a) zxy(b) - zxy(a) yzx(b).
TWINRAY_REFINE_INLINE Vec4 yzx(const Vec4& a) { return {__builtin_shufflevector(a.v, a.v, 1, 2, 0, 3)}; }
TWINRAY_REFINE_INLINE Vec4 zxy(const Vec4& a) { return {__builtin_shufflevector(a.v, a.v, 2, 0, 1, 3)}; }

// The sums of the components of x, y, z and w, as (sum x, sum y, sum z, sum w): (x0 + x1) + (x2 + x3) with
// x3 = 0, so each term passes through at most two roundings.
TWINRAY_REFINE_INLINE Vec4 sums(const Vec4& x, const Vec4& y, const Vec4& z, const Vec4& w) {
  const Vec4d xy = __builtin_shufflevector(x.v, y.v, 0, 4, 2, 6) + __builtin_shufflevector(x.v, y.v, 1, 5, 3, 7);
  const Vec4d zw = __builtin_shufflevector(z.v, w.v, 0, 4, 2, 6) + __builtin_shufflevector(z.v, w.v, 1, 5, 3, 7);
  return {__builtin_shufflevector(xy, zw, 0, 1, 4, 5) + __builtin_shufflevector(xy, zw, 2, 3, 6, 7)};
}

// The ray in double, with what every refinement of it reuses. Built once per ray.
struct RefineRay {
  Vec4 o{{0.0, 0.0, 0.0, 0.0}};
  Vec4 d{{0.0, 0.0, 1.0, 0.0}};
  Vec4 abs_d{{0.0, 0.0, 1.0, 0.0}};
};

// What the bounds of numerator and denominator give for every quotient n^ * r with r = fl(1/d^):
// |n/d - n^ r| <= (|n^| Ed + |d^| En) w + 3u |n^ r|, scaled for its own rounding (see the header). u, v use
// it (certify_barycentrics); t divides directly (t_ends). r and w are filled by quotient_of, for the winner
// only; crossing_sums fills abs_den and den_err.
struct Quotient {
  double r = 0.0;        // fl(1 / den)
  double w = 0.0;        // at least 1 / ((|den| - Ed) |den|) up to a few roundings: r^2 (1 + 2 Ed |r|)
  double abs_den = 0.0;
  double den_err = 0.0;
};

// Everything t and u, v share: the triangle's edges, a = p0 - o, the normal's numerators den = d.n and
// a.n with their bounds.
struct Crossing {
  Vec4 p0, e1, e2, a;
  Vec4 n;  // e1 x e2
  Quotient quotient;
  double num = 0.0, num_err = 0.0;  // a.n and its bound
  double den = 0.0;  // d.n (its bound is quotient.den_err)
  bool den_certain = false;  // whether den's sign is certain (crossing_sums returned true)
};

// e1 x e2 and its absolute terms: (|e1_j e2_k| + |e1_k e2_j|)_i.
TWINRAY_REFINE_INLINE void cross_with_terms(const Vec4& e1, const Vec4& e2, Vec4& n, Vec4& n_terms) {
  const Vec4 m1 = yzx(e1) * zxy(e2), m2 = zxy(e1) * yzx(e2);
  n = m1 - m2;
  n_terms = abs(m1) + abs(m2);
}

// Fills `c` but for the quotient's r and w (quotient_of): false when den's sign is not certain (|den| <= 2 Ed:
// then neither t_ends nor w would bound the exact values).
TWINRAY_REFINE_INLINE bool crossing_sums(const RefineRay& ray, const Vec4& p0, const Vec4& p1, const Vec4& p2,
                                         Crossing& c) {
  c.p0 = p0;
  c.e1 = p1 - p0;
  c.e2 = p2 - p0;
  c.a = p0 - ray.o;
  Vec4 n_terms;
  cross_with_terms(c.e1, c.e2, c.n, n_terms);
  // (den, its absolute terms, a.n, its absolute terms)
  const Vec4 s = sums(ray.d * c.n, ray.abs_d * n_terms, c.a * c.n, abs(c.a) * n_terms);
  Quotient& q = c.quotient;
  q.den_err = kCrossingBound * s.v[1];
  q.abs_den = std::fabs(s.v[0]);
  c.num = s.v[2];
  c.num_err = kCrossingBound * s.v[3];
  c.den = s.v[0];
  c.den_certain = q.abs_den > 2.0 * q.den_err;
  return c.den_certain;
}
// The quotient's r and w once den's sign is certain (the barycentrics' bound): r = fl(1 / den), and
// 1 / (1 - x) <= 1 + 2x for 0 <= x <= 1/2 gives w without a second division. Only the winner of a closest-hit
// query needs them (refine_uv_kept); a candidate's t takes its own route (t_ends), and a membership test may
// not even need that (certainly_inside).
TWINRAY_REFINE_INLINE void quotient_of(double den, Quotient& q) {
  q.r = 1.0 / den;
  q.w = q.r * q.r * (1.0 + 2.0 * q.den_err * std::fabs(q.r));
}

// Whether the exact t = N / D of a crossing whose den's sign is certain lies strictly between tmin and
// min(tmax, the largest float), decided without the quotient; for a valid ray's 0 <= tmin <= tmax (the
// margins below assume both sides' terms are not negative). With s the sign of D (certain: |D^| > 2 Ed),
// t > tmin  <=>  s N - tmin |D| > 0,  which holds when  (s N^ - En) - tmin (|D^| + Ed) > 0,  and
// t < tmax  <=>  tmax |D| - s N > 0,  which holds when  tmax (|D^| - Ed) - (s N^ + En) > 0.
// Each side is evaluated with at most two roundings of relative size u = 2^-53 (a sum, then a product), so
// a computed side exceeds the exact one by at most a factor (1 + u)^2 / (1 - u) < 1 + 4u, and the factors
// 1 +- 2^-48 (32 u, themselves rounded once) cover that with room; a side of one sign (s N^ + En < 0)
// passes trivially. Rounding is monotonic and the two ends are floats, so the rounded t then lies in
// [tmin, tmax] and is finite: the same answer as the interval test of t_ends, for fewer operations on
// the chain (no division). Flush-to-zero only moves a computed side toward 0, where the strict test fails.
TWINRAY_REFINE_INLINE bool certainly_inside(const Crossing& c, float tmin, float tmax) {
  const double s_num = c.den > 0.0 ? c.num : -c.num;
  const Quotient& q = c.quotient;
  const double lower = static_cast<double>(tmin) * (q.abs_den + q.den_err);
  const double upper = static_cast<double>(tmax < 0x1.fffffep127f ? tmax : 0x1.fffffep127f) * (q.abs_den - q.den_err);
  return s_num - c.num_err > lower * (1.0 + 0x1p-48) && upper * (1.0 - 0x1p-48) > s_num + c.num_err;
}

// Whether the exact t of a crossing whose den's sign is certain is at most -2^-126, so that its rounded t
// (flushed to zero or not) lies below every tmin >= 0: decided without the quotient. With s the sign of D,
// sN <= sN^ + En =: a and 2^-126 |D| <= 2^-126 (|D^| + Ed) <= 0.375 b with b = 2^-124 |D^| (exact: a power of
// two times a double far above 2^-1022) and Ed < |D^| / 2; the computed fl(fl(a) + b) < 0 means a (1 + d) < -b,
// |d| <= 2^-53, so sN + 2^-126 |D| <= a + 0.375 b < -b (1 - 2^-53) + 0.375 b < 0, i.e. t = sN / |D| < -2^-126.
// A sum flushed to zero (FTZ) fails the strict test.
TWINRAY_REFINE_INLINE bool certainly_behind(const Crossing& c) {
  const double s_num = c.den > 0.0 ? c.num : -c.num;
  return (s_num + c.num_err) + 0x1p-124 * c.quotient.abs_den < 0.0;
}

// normalize(n) rounded to float, (0, 0, 1) for a zero n (collinear vertices, which the edge test never hits):
// the geometric normal. One function for triangle_geometric_normal and refine_uv's, so both give the same
// bits.
inline glm::vec3 unit_normal(double nx, double ny, double nz) {
  const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
  if (!(len > 0.0)) return glm::vec3(0.0f, 0.0f, 1.0f);
  return glm::vec3(static_cast<float>(nx / len), static_cast<float>(ny / len), static_cast<float>(nz / len));
}
// The same bits from (x, y, z, 0): the three quotients as one vector division (each lane the same IEEE
// division), so the winner's tail waits for one division after the square root instead of three in a row.
TWINRAY_REFINE_INLINE glm::vec3 unit_normal(const Vec4& n) {
  const double nx = n.v[0], ny = n.v[1], nz = n.v[2];
  const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
  if (!(len > 0.0)) return glm::vec3(0.0f, 0.0f, 1.0f);
  const Vec4d q = n.v / len;
  return glm::vec3(static_cast<float>(q[0]), static_cast<float>(q[1]), static_cast<float>(q[2]));
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

// The t interval of a crossing whose den's sign is certain (crossing_sums returned true): the floats that the
// ends of an interval around the exact N / D round to, widened past their own rounding (every real in it
// rounds to a float between lo and hi, rounding being monotonic; lo == hi certifies t's rounding).
// Two divisions issued side by side right after the sums, so that the chain from den to the ends is one
// division, a product, two additions and the conversions; the reciprocal's route (x = N^ r, then w, the
// bound, the slack) was about 15 cycles longer, all on the candidate's dependency chain, and only u, v need
// r. With x = fl(N^ / D^), E = fl(fl(|N^| Ed) + fl(|D^| En)), P = fl(fl(|D^| - Ed) |D^|), A = fl(E / P):
//   |N/D - N^/D^| <= (|N^| Ed + |D^| En) / ((|D^| - Ed) |D^|)  (the quotient bound of the header),
//   |N^/D^ - x| <= u |x| / (1 - u),
// and fl(x - slack) exceeds x - slack by at most u (|x| + slack) (x + slack likewise), so the ends enclose
// N / D when slack (1 - u) >= (|N^| Ed + |D^| En) / ((|D^| - Ed) |D^|) + 2u |x| (1 + u). slack =
// fl(A + fl(3u |x|)): 3u |x| after its own and the sum's rounding and the (1 - u) covers 2u |x| (1 + u), and
// the factor 1 + 2^-40 that Ed and En carry beyond the 10u the header derives (kCrossingBound) covers A's
// five roundings and the same two (at most 8u). |D^| - Ed > |D^| / 2 > 0 (den
// certain, and |D^| >= 20u 2^-447 since Ed is at least 10u times a non-zero product), so P lies in
// [2^-995, 2^782], E below 2^782 and A, x below 2^890: every intermediate is normal or zero and finite in
// double, and flush-to-zero does not touch them. An end beyond float's range converts to an infinity, which
// is never certified and compares as it should against tmin and tmax.
TWINRAY_REFINE_INLINE Ends t_ends(const Crossing& c) {
  const Quotient& q = c.quotient;
  const double x = c.num / c.den;
  const double e = std::fabs(c.num) * q.den_err + q.abs_den * c.num_err;
  const double a = e / ((q.abs_den - q.den_err) * q.abs_den);
  const double slack = a + std::fabs(x) * (3.0 * kUnit);
  return {static_cast<float>(x - slack), static_cast<float>(x + slack)};
}

// q clamped to [0, 1], if certain, per lane (u and v), where `slack` covers both the error of q (within err of
// the exact value) and the roundings of q -+ slack: err + 2u |q| or more, as in round_ends. 0 and 1 are
// floats, so clamping after rounding is the same as rounding after clamping. The ends of the interval are clamped in
// double and rounded; a lane is certain when both round to the same float and that float is 0 from an
// interval at or below 0, or normal (a value that rounds into the subnormal range goes to the exact path).
TWINRAY_REFINE_INLINE bool certify_barycentrics(const Vec2d& q, const Vec2d& slack, float& u, float& v) {
  const Vec2d zero = {0.0, 0.0}, one = {1.0, 1.0};
  Vec2d lo = q - slack, hi = q + slack;
  // <= rather than <: an end of -0 becomes +0, the float the exact path returns for u or v clamped to 0.
  lo = lo <= zero ? zero : (lo > one ? one : lo);
  hi = hi <= zero ? zero : (hi > one ? one : hi);
  const float lo_u = static_cast<float>(lo[0]), hi_u = static_cast<float>(hi[0]);
  const float lo_v = static_cast<float>(lo[1]), hi_v = static_cast<float>(hi[1]);
  if (!(lo_u == hi_u && (lo_u >= 0x1p-125f || hi[0] == 0.0))) return false;
  if (!(lo_v == hi_v && (lo_v >= 0x1p-125f || hi[1] == 0.0))) return false;
  u = lo_u;
  v = lo_v;
  return true;
}

// u = e2.(a x d) / den and v = -e1.(a x d) / den, certified as above. a x d is computed as h x d with
// h = a - t d, the vector from p0 to the crossing (the same cross product, since t d x d = 0): for a ray whose
// a is nearly parallel to d (every ray that meets a small triangle far away) a x d itself cancels to a few
// digits, h x d does not. h is formed without losing a: t d_k is exact (a product of two floats), the
// rounding error of a_k = p0_k - o_k is recovered exactly by TwoSum (Knuth) and added back, so each h_k is
// within 2u |h_k| + u^2 |a_k| of its exact value; with the remaining roundings (a product, a difference, a
// product, two additions and e's own) each term passes through at most 8, and the u^2 |a| part adds at most
// u^2 (1 + 2u) (|a_j| |d_k| + |a_k| |d_j|) to component i of h x d, so 2^-100 |e|.(|a| x' |d|) bounds its
// share of u_num's error (x' the cross product with both products added: the absolute terms), evaluated with
// the other absolute terms as one sum (2^-100 / kSumBound is the factor that puts it on their scale).
TWINRAY_REFINE_INLINE bool certify_barycentrics(const RefineRay& ray, const Crossing& c, const Quotient& quotient,
                                                 float t, float& u, float& v) {
  const Vec4 back = c.a - c.p0;  // TwoSum of p0_k and -o_k: a_k + error is exactly p0_k - o_k
  const Vec4 error = (c.p0 - (c.a - back)) + (-ray.o - back);
  const Vec4 h = (c.a - static_cast<double>(t) * ray.d) + error;
  const Vec4 m1 = yzx(h) * zxy(ray.d), m2 = zxy(h) * yzx(ray.d);
  const Vec4 q = m1 - m2;
  const Vec4 abs_a = abs(c.a);
  const Vec4 a_terms = yzx(abs_a) * zxy(ray.abs_d) + zxy(abs_a) * yzx(ray.abs_d);
  const Vec4 terms = (abs(m1) + abs(m2)) + (0x1p-100 / kSumBound) * a_terms;
  // (e2.q, e1.q, and the absolute terms of their bounds)
  const Vec4 s = sums(c.e2 * q, c.e1 * q, abs(c.e2) * terms, abs(c.e1) * terms);
  const Vec2d num = {s.v[0], -s.v[1]}, err_sums = {s.v[2], s.v[3]};
  const Vec2d uv = num * quotient.r;
  // The slack of certify_barycentrics, ((|num| Ed + |D| En) w + 3u |uv|)(1 + 2^-40) + 2u |uv| with En =
  // kSumBound err_sums, regrouped so that the chain after the sums is one product level and two additions
  // (thirteenth round, docs/bvh-backend.md: the winner's tail is on every closest-hit query's path):
  // |num| coef_num + err_sums coef_err + |uv| coef_uv, with coef_num = fl(fl(Ed w)(1 + 2^-40)) and coef_err =
  // fl(fl(|D| w) kCrossingBound) (kCrossingBound = kSumBound (1 + 2^-40) exactly) computed from the quotient
  // alone, before the sums are ready, and coef_uv = 5u + 3u 2^-40 (exact: 43 bits). Each of the first two
  // terms passes through at most 10 roundings counting w's own five (Ed w or |D| w, the factor, the product
  // with |num| or err_sums, two additions), a factor (1 - u)^10 > 1 - 2^-49, which the 1 + 2^-40 still covers
  // with more than 2^-41 to spare, as the header's derivation asks; the third passes through two (its product
  // and the last addition), so it is at least (5u + 3u 2^-40)(1 - u)^2 |uv|, no less than the 3u (1 +
  // 2^-40)(1 - u)^3 + 2u (1 - u) that the grouping before this round guaranteed. So the slack bounds what it
  // did before.
  const double coef_num = (quotient.den_err * quotient.w) * (1.0 + 0x1p-40);
  const double coef_err = (quotient.abs_den * quotient.w) * kCrossingBound;
  constexpr double coef_uv = 5.0 * kUnit + 3.0 * kUnit * 0x1p-40;
  const Vec2d slack = (abs(num) * coef_num + err_sums * coef_err) + abs(uv) * coef_uv;
  return certify_barycentrics(uv, slack, u, v);
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
// The exact path for vertices given as glm vectors, read again from their memory: the hot path need not
// keep copies of them alive for it. (A leaf test passes its own, reading its block.)
template <typename Vec3>
[[gnu::cold, gnu::noinline]] inline bool exact_crossing_of(const RefineRay& ray, const Vec3& p0, const Vec3& p1,
                                                           const Vec3& p2, float& t, float& u, float& v) {
  return exact_crossing(store(ray.o), store(ray.d), glm::dvec3(p0), glm::dvec3(p1), glm::dvec3(p2), t, u, v);
}

// The crossing parameter of the line o + t d with triangle (p0, p1, p2), which the caller's edge test has
// accepted: false when there is no crossing (see above) or its correctly rounded t lies outside
// [tmin, tmax]; otherwise the correctly rounded t. Inputs are doubles holding floats; `exact(t, u, v)` is
// the exact path for the same triangle. `c` is left holding the crossing (e1, e2, a, e1 x e2, den): a
// closest-hit traversal keeps the winner's and certifies its u, v from it (refine_uv_kept) instead of
// computing the same numbers again.
// kBehindFirst (bvh8's closest-hit leaves; a valid ray's tmin >= 0): a crossing certainly_behind the origin
// is dropped before the quotient.
template <bool kBehindFirst = false, typename Exact>
TWINRAY_REFINE_INLINE bool refine_t_kept_v(const RefineRay& ray, const Vec4& p0, const Vec4& p1, const Vec4& p2,
                                           float tmin, float tmax, float& t_out, Crossing& c, const Exact& exact) {
  float t = 0.0f;
  bool certain = false;
  // The reciprocal and w that u, v need are left to refine_uv_kept (the winner only): t_ends needs neither.
  if (crossing_sums(ray, p0, p1, p2, c)) {
    if (kBehindFirst && certainly_behind(c)) return false;
    const Ends ends = t_ends(c);
    // Certainly outside: every t within the bound rounds below tmin or above tmax. (Most rejected
    // candidates end here: the triangle a secondary ray starts from, crossings beyond the closest hit.)
    if (ends.hi < tmin || ends.lo > tmax) return false;
    certain = ends.certified();
    t = ends.lo;
  }
  if (!certain) {
    float u, v;
    if (!exact(t, u, v)) return false;
  }
  if (!(t >= tmin && t <= tmax)) return false;
  t_out = t;
  return true;
}
template <typename Exact>
TWINRAY_REFINE_INLINE bool refine_t_v(const RefineRay& ray, const Vec4& p0, const Vec4& p1, const Vec4& p2,
                                      float tmin, float tmax, float& t_out, const Exact& exact) {
  Crossing c;
  return refine_t_kept_v(ray, p0, p1, p2, tmin, tmax, t_out, c, exact);
}

// Whether that correctly rounded t lies in [tmin, tmax], without the t itself (any-hit queries): an
// interval inside [tmin, tmax] decides, certified or not. With kDivisionFreeFirst, certainly_inside is
// asked before the quotient is computed (the same answers; a shorter chain for a crossing well inside, a
// few instructions more for one that is not): `bvh` and `brute` use it; `bvh8`'s kernels do not yet (on
// them it cost 0.5% more instructions on dragon shadow rays, docs/bvh-backend.md, sixth round).
//
// With kBySign (bvh8's any-hit leaves; a valid ray's 0 <= tmin <= tmax), the sign of the crossing's t decides
// which division-free test is asked first: a crossing behind the origin (the triangle a secondary ray starts
// from, 0.6 of the 1.13 candidates of a dragon shadow ray) is dropped by certainly_behind, one ahead is
// accepted by certainly_inside; either failing, the quotient decides as without it. The same answers.
template <bool kDivisionFreeFirst = false, bool kBySign = false, typename Exact>
TWINRAY_REFINE_INLINE bool refine_in_interval_v(const RefineRay& ray, const Vec4& p0, const Vec4& p1, const Vec4& p2,
                                                float tmin, float tmax, const Exact& exact) {
  Crossing c;
  if (crossing_sums(ray, p0, p1, p2, c)) {
    if constexpr (kBySign) {
      if ((c.den > 0.0 ? c.num : -c.num) < 0.0) {
        if (certainly_behind(c)) return false;
      } else if (certainly_inside(c, tmin, tmax)) {
        return true;
      }
    }
    if (kDivisionFreeFirst && certainly_inside(c, tmin, tmax)) return true;
    const Ends ends = t_ends(c);
    if (ends.hi < tmin || ends.lo > tmax) return false;
    // Strictly inside: the rounded t lies between the ends, so in [tmin, tmax]. Strict, because an end
    // flushed to zero (FTZ) only bounds t up to 2^-126, and a normal tmin or tmax on the other side of a
    // zero end is at least that far away; and hi < tmax also makes hi, so t, finite.
    if (ends.lo > tmin && ends.hi < tmax) return true;
  }
  float t;
  return refine_t_v(ray, p0, p1, p2, tmin, tmax, t, exact);
}

// The barycentrics (u weights p1, v weights p2) of a crossing `c` that refine_t_v left, correctly rounded
// after clamping to [0, 1]; `t` is what refine_t_v returned with it. Kept apart so that a closest-hit
// traversal computes them once, for the winner; with its geometric normal when `ng` is given (from the same
// e1 x e2).
template <typename Exact>
TWINRAY_REFINE_INLINE void refine_uv_kept(const RefineRay& ray, const Crossing& c, float t, float& u, float& v,
                                          glm::vec3* ng, const Exact& exact) {
  if (ng != nullptr) *ng = unit_normal(c.n);
  if (c.den_certain) {
    // The reciprocal and w here, for the winner only (the candidates' t needs neither, t_ends): the division
    // starts with the query's tail and is ready before u, v's numerators are.
    Quotient quotient = c.quotient;
    quotient_of(c.den, quotient);
    if (certify_barycentrics(ray, c, quotient, t, u, v)) return;
  }
  float t_exact;
  exact(t_exact, u, v);
}
// The same from the vertices, when the crossing was not kept: crossing() gives the same numbers again.
template <typename Exact>
TWINRAY_REFINE_INLINE void refine_uv_v(const RefineRay& ray, const Vec4& p0, const Vec4& p1, const Vec4& p2, float t,
                                       float& u, float& v, glm::vec3* ng, const Exact& exact) {
  Crossing c;
  crossing_sums(ray, p0, p1, p2, c);
  refine_uv_kept(ray, c, t, u, v, ng, exact);
}

// The entry points, for vertices and rays given as glm vectors of floats (the leaf tests) or of doubles
// holding floats (the exact backend, tests): the vectors stay inside. `exact` as above; by default
// exact_crossing_of the same vertices.
template <typename Vec3>
TWINRAY_REFINE_INLINE void set_ray(RefineRay& ray, const Vec3& o, const Vec3& d) {
  ray.o = load(o);
  ray.d = load(d);
  ray.abs_d = abs(ray.d);
}
template <bool kBehindFirst = false, typename Vec3, typename Exact>
TWINRAY_REFINE_INLINE bool refine_t(const RefineRay& ray, const Vec3& p0, const Vec3& p1, const Vec3& p2, float tmin,
                                    float tmax, float& t, Crossing& kept, const Exact& exact) {
  return refine_t_kept_v<kBehindFirst>(ray, load(p0), load(p1), load(p2), tmin, tmax, t, kept, exact);
}
template <typename Vec3, typename Exact>
TWINRAY_REFINE_INLINE bool refine_t(const RefineRay& ray, const Vec3& p0, const Vec3& p1, const Vec3& p2, float tmin,
                                    float tmax, float& t, const Exact& exact) {
  return refine_t_v(ray, load(p0), load(p1), load(p2), tmin, tmax, t, exact);
}
template <bool kDivisionFreeFirst = false, bool kBySign = false, typename Vec3, typename Exact>
TWINRAY_REFINE_INLINE bool refine_in_interval(const RefineRay& ray, const Vec3& p0, const Vec3& p1, const Vec3& p2,
                                              float tmin, float tmax, const Exact& exact) {
  return refine_in_interval_v<kDivisionFreeFirst, kBySign>(ray, load(p0), load(p1), load(p2), tmin, tmax, exact);
}
template <typename Vec3, typename Exact>
TWINRAY_REFINE_INLINE void refine_uv(const RefineRay& ray, const Vec3& p0, const Vec3& p1, const Vec3& p2, float t,
                                     float& u, float& v, glm::vec3* ng, const Exact& exact) {
  refine_uv_v(ray, load(p0), load(p1), load(p2), t, u, v, ng, exact);
}
template <typename Vec3>
TWINRAY_REFINE_INLINE bool refine_t(const RefineRay& ray, const Vec3& p0, const Vec3& p1, const Vec3& p2, float tmin,
                                    float tmax, float& t) {
  return refine_t(ray, p0, p1, p2, tmin, tmax, t,
                  [&](float& te, float& ue, float& ve) { return exact_crossing_of(ray, p0, p1, p2, te, ue, ve); });
}
template <bool kDivisionFreeFirst = false, bool kBySign = false, typename Vec3>
TWINRAY_REFINE_INLINE bool refine_in_interval(const RefineRay& ray, const Vec3& p0, const Vec3& p1, const Vec3& p2,
                                              float tmin, float tmax) {
  return refine_in_interval<kDivisionFreeFirst, kBySign>(ray, p0, p1, p2, tmin, tmax,
                            [&](float& te, float& ue, float& ve) { return exact_crossing_of(ray, p0, p1, p2, te, ue, ve); });
}
template <typename Vec3>
TWINRAY_REFINE_INLINE void refine_uv(const RefineRay& ray, const Vec3& p0, const Vec3& p1, const Vec3& p2, float t,
                                     float& u, float& v, glm::vec3* ng = nullptr) {
  refine_uv(ray, p0, p1, p2, t, u, v, ng,
            [&](float& te, float& ue, float& ve) { return exact_crossing_of(ray, p0, p1, p2, te, ue, ve); });
}
// The geometric normal of a triangle: unit_normal of the same e1 x e2 as crossing() computes.
template <typename Vec3>
TWINRAY_REFINE_INLINE glm::vec3 geometric_normal(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const Vec4 q0 = load(p0);
  Vec4 n, n_terms;
  cross_with_terms(load(p1) - q0, load(p2) - q0, n, n_terms);
  return unit_normal(n);
}

#undef TWINRAY_REFINE_INLINE

}  // namespace refine_detail

// The same for a ray and a triangle given as doubles holding floats (the exact backend, tests).
inline bool refine_triangle_t(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& p0, const glm::dvec3& p1,
                              const glm::dvec3& p2, float tmin, float tmax, float& t_out) {
  refine_detail::RefineRay ray;
  refine_detail::set_ray(ray, o, d);
  return refine_detail::refine_t(ray, p0, p1, p2, tmin, tmax, t_out);
}
inline void refine_triangle_uv(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& p0, const glm::dvec3& p1,
                               const glm::dvec3& p2, float t, float& u, float& v) {
  refine_detail::RefineRay ray;
  refine_detail::set_ray(ray, o, d);
  refine_detail::refine_uv(ray, p0, p1, p2, t, u, v);
}

// Both: what a leaf test reports for a candidate its edge test accepted.
inline bool refine_triangle_hit(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& p0, const glm::dvec3& p1,
                                const glm::dvec3& p2, float tmin, float tmax, float& t, float& u, float& v) {
  if (!refine_triangle_t(o, d, p0, p1, p2, tmin, tmax, t)) return false;
  refine_triangle_uv(o, d, p0, p1, p2, t, u, v);
  return true;
}

}  // namespace twinray
