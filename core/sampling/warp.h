#pragma once
// Warps from the unit square to the domains a path tracer samples (hemisphere, sphere, cone, triangle),
// their densities, an orthonormal shading frame, and the MIS power heuristic.
//
// Every warp takes u in [0,1)^2 and returns a point whose density with respect to the natural measure
// of the domain (solid angle for directions, area for barycentrics) is the matching *_pdf function.
// Directions are in a local frame with +Z as the pole; Frame moves them to and from world space.

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace twinray {

inline constexpr float kPi = std::numbers::pi_v<float>;
inline constexpr float kInvPi = std::numbers::inv_pi_v<float>;
inline constexpr float kInv2Pi = 0.5f * std::numbers::inv_pi_v<float>;
inline constexpr float kInv4Pi = 0.25f * std::numbers::inv_pi_v<float>;

// sqrt that tolerates the tiny negative arguments rounding produces for quantities that are >= 0 in
// exact arithmetic (e.g. 1 - z^2 with |z| rounded to just above 1).
inline float safe_sqrt(float x) { return std::sqrt(std::max(x, 0.0f)); }

// sin and cos of x for |x| <= pi/4, by their Taylor polynomials of degree 9 and 10: the first omitted
// terms, x^11/11! and x^12/12!, are below 2e-9 there, under a float ulp of the results, so the values are
// as good as libm's (a few ulps of rounding in the evaluation) without a call, a range reduction or a
// branch on the argument. Used by the concentric map, whose angles stay within a quarter turn.
inline void sin_cos_quarter(float x, float& sin_x, float& cos_x) {
  const float x2 = x * x;
  sin_x = x * (1.0f + x2 * (-1.0f / 6.0f + x2 * (1.0f / 120.0f + x2 * (-1.0f / 5040.0f + x2 * (1.0f / 362880.0f)))));
  cos_x = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24.0f + x2 * (-1.0f / 720.0f + x2 * (1.0f / 40320.0f + x2 * (-1.0f / 3628800.0f)))));
}

// Shirley–Chiu concentric map from [0,1)^2 to the unit disk. Unlike the polar map (r = sqrt(u0)) it keeps
// neighbouring square cells neighbours on the disk with little shape distortion, so stratified or
// low-discrepancy points stay well spread after warping.
//
// Branch-free: which wedge a point falls in is a coin toss for random u, and a mispredicted branch costs
// more than computing both candidates and selecting one.
inline glm::vec2 sample_concentric_disk(glm::vec2 u) {
  const float a = 2.0f * u.x - 1.0f;
  const float b = 2.0f * u.y - 1.0f;
  // The angle is phi = pi/4 (b/a) in the wedges around the x axis and pi/2 - pi/4 (a/b) in those around
  // the y axis, where cos(phi) = sin(pi/4 (a/b)) and sin(phi) = cos(pi/4 (a/b)).
  const bool x_wedge = std::abs(a) > std::abs(b);
  const float num = x_wedge ? b : a;
  const float den = x_wedge ? a : b;
  const float r = den;
  float s, c;
  sin_cos_quarter(den != 0.0f ? (kPi / 4.0f) * (num / den) : 0.0f, s, c);
  return x_wedge ? glm::vec2(r * c, r * s) : glm::vec2(r * s, r * c);
}

// Malley's method: a uniform disk point lifted onto the hemisphere is cosine distributed.
inline glm::vec3 sample_cosine_hemisphere(glm::vec2 u) {
  const glm::vec2 d = sample_concentric_disk(u);
  return glm::vec3(d.x, d.y, safe_sqrt(1.0f - d.x * d.x - d.y * d.y));
}
// Density w.r.t. solid angle; 0 below the horizon (those directions are never produced).
inline float cosine_hemisphere_pdf(float cos_theta) { return cos_theta > 0.0f ? cos_theta * kInvPi : 0.0f; }

inline glm::vec3 sample_uniform_sphere(glm::vec2 u) {
  const float z = 1.0f - 2.0f * u.x;
  const float r = safe_sqrt(1.0f - z * z);
  const float phi = 2.0f * kPi * u.y;
  return glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
}
inline float uniform_sphere_pdf() { return kInv4Pi; }

// Uniform directions inside the cone {cos(theta) >= cos_theta_max} around +Z, given 1 - cos_theta_max.
//
// Why the "one minus cos" form: a light of radius r at distance d subtends sin^2(theta_max) = (r/d)^2; for
// a small or distant light cos_theta_max = sqrt(1 - (r/d)^2) rounds to exactly 1 in float once r/d < ~3e-4,
// and a cone built from it collapses to a line (pdf = inf). Passing 1 - cos directly keeps full relative
// precision; sin(theta) is then formed as sqrt(x (2 - x)) with x = 1 - cos(theta), which never subtracts
// nearly equal numbers either.
inline glm::vec3 sample_uniform_cone_one_minus_cos(glm::vec2 u, float one_minus_cos_max) {
  const float one_minus_cos = u.x * one_minus_cos_max;
  const float cos_theta = 1.0f - one_minus_cos;
  const float sin_theta = safe_sqrt(one_minus_cos * (2.0f - one_minus_cos));
  const float phi = 2.0f * kPi * u.y;
  return glm::vec3(sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta);
}
inline float uniform_cone_pdf_one_minus_cos(float one_minus_cos_max) {
  return one_minus_cos_max > 0.0f ? 1.0f / (2.0f * kPi * one_minus_cos_max) : 0.0f;
}

// 1 - cos(theta) from sin^2(theta) for theta in [0, pi/2], without cancellation:
// 1 - cos = sin^2 / (1 + cos). Use this for spheres/discs seen from afar (sin^2 = (r/d)^2).
inline float one_minus_cos_from_sin2(float sin2_theta) {
  const float s2 = std::clamp(sin2_theta, 0.0f, 1.0f);
  return s2 / (1.0f + std::sqrt(1.0f - s2));
}

// Convenience forms taking cos(theta_max). 1 - cos_theta_max is exact in float whenever
// cos_theta_max >= 0.5 (Sterbenz), so these lose nothing *beyond* what rounding cos_theta_max itself lost;
// callers that start from a squared sine should use the *_one_minus_cos forms above.
inline glm::vec3 sample_uniform_cone(glm::vec2 u, float cos_theta_max) {
  return sample_uniform_cone_one_minus_cos(u, 1.0f - cos_theta_max);
}
inline float uniform_cone_pdf(float cos_theta_max) { return uniform_cone_pdf_one_minus_cos(1.0f - cos_theta_max); }

// Uniform barycentrics (b0, b1, b2) on a triangle, density 1 / area. Uses the low-distortion split of the
// square into two triangles (Heitz 2019) instead of the classic sqrt fold: no sqrt, and nearby u map to
// nearby points, which keeps stratification. b2 is formed last as 1 - b0 - b1 so the three always sum to 1.
inline glm::vec3 sample_uniform_triangle(glm::vec2 u) {
  // Both halves computed, one selected (no branch on a coin toss).
  const bool lower = u.x < u.y;
  const float h = 0.5f * (lower ? u.x : u.y);
  const float b0 = lower ? h : u.x - h;
  const float b1 = lower ? u.y - h : h;
  return glm::vec3(b0, b1, 1.0f - b0 - b1);
}

// Orthonormal right-handed frame (s, t, n) with s x t = n. from_normal is the branchless construction of
// Duff et al. 2017 ("Building an Orthonormal Basis, Revisited"), which stays orthonormal to float precision
// for every unit n, including n = (0, 0, -1) where Frisvad's original divides by zero.
struct Frame {
  glm::vec3 s{1.0f, 0.0f, 0.0f};
  glm::vec3 t{0.0f, 1.0f, 0.0f};
  glm::vec3 n{0.0f, 0.0f, 1.0f};

  // n must be unit length.
  static Frame from_normal(glm::vec3 normal) {
    const float sign = std::copysign(1.0f, normal.z);
    const float a = -1.0f / (sign + normal.z);
    const float b = normal.x * normal.y * a;
    Frame f;
    f.s = glm::vec3(1.0f + sign * normal.x * normal.x * a, sign * b, -sign * normal.x);
    f.t = glm::vec3(b, sign + normal.y * normal.y * a, -normal.y);
    f.n = normal;
    return f;
  }

  glm::vec3 to_local(glm::vec3 v) const { return glm::vec3(glm::dot(v, s), glm::dot(v, t), glm::dot(v, n)); }
  glm::vec3 to_world(glm::vec3 v) const { return v.x * s + v.y * t + v.z * n; }
};

// Veach's power heuristic with beta = 2 for nf samples from f and ng from g: (nf f)^2 / ((nf f)^2 + (ng g)^2).
// Written as 1 / (1 + r^2) with r = g' / f' so it never forms inf/inf: an infinite f pdf (a delta
// distribution) gets weight 1, an infinite g pdf weight 0, f = 0 weight 0, and squares that overflow or
// underflow push the weight to 0 or 1 instead of NaN. Both infinite: 0.5 (undefined in theory; symmetric).
inline float power_heuristic(float nf, float f_pdf, float ng, float g_pdf) {
  const float f = nf * f_pdf;
  const float g = ng * g_pdf;
  if (std::isinf(f)) return std::isinf(g) ? 0.5f : 1.0f;
  if (!(f > 0.0f)) return 0.0f;
  const float r = g / f;
  return 1.0f / (1.0f + r * r);
}

}  // namespace twinray
