#pragma once
// Light connections: a restricted bidirectional strategy that the path integrator adds to its own two
// (IntegratorSettings::light_connections, docs/rendering.md#light-connections).
//
// Each camera sample traces M light subpaths of one segment: a point y0 on a surface light
// (LightSampler::sample_emission: area density pE, selection included), a cosine-distributed direction, its
// first hit y1. Every non-delta camera vertex x (reached by at most kLightConnectionMaxDepth segments) is
// joined to every y1 that is non-delta by a shadow ray. That generates the paths ... x y1 y0: light reflected
// once at y1 before it reaches x. The path tracer generates the same paths two ways, from x: BSDF sampling at
// y1 that hits the light (A), and the light sample at y1 (B). The three are combined with the power heuristic
// with sample counts n, n, M (n = K when x is the vertex split K ways, else 1); the densities of (y1, y0) given
// the path up to x, in area measure and each divided by their common factor cos(y0) / |y1 - y0|^2, are
//   A = n p(y1) pdf_bsdf(y1 -> y0),   B = n p(y1) pdf_light(y1 -> y0),   C = M pE(y0) |cos(n_y1, y1 -> y0)| / pi,
// with p(y1) = pdf_bsdf(x -> y1) |cos(n_y1, y1 -> x)| / |y1 - x|^2 the path tracer's area density of y1 and the
// pdf_* solid-angle densities. A strategy's weight is its value squared over the sum of the three squared:
// whichever of them apply to a path, the weights sum to 1, so the sum of the three estimators is unbiased.
// On the path tracer's side only C is new: C / (n p(y1)) = connection_factor(...) * pE(y0) |cos(n_y1, y1 -> y0)|.
// The roulette and the light subpaths' reuse at several camera vertices leave every estimator unbiased.

#include "core/render/light_transport.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>

namespace twinray {

// Camera vertices reached by more segments make no connections. Measured on the Cornell box (instructions x
// noise relMSE against no connections, docs/rendering.md#light-connections): depth 1 only 1.004, up to 2
// 0.898, up to 3 0.881, unlimited 0.954 (the deeper connections cost as much and their paths carry little).
inline constexpr int kLightConnectionMaxDepth = 3;

// At a vertex x2 behind a non-delta camera vertex x1 that made connections: the factor the path tracer
// multiplies by pE(x3) |cos(n2, x2 -> x3)| (x3 on a light) to obtain C / (n p(x2)) in the units of its own
// solid-angle densities, i.e. (M / n) d12^2 / (pi pdf_bsdf(x1 -> x2) |cos(n2, x2 -> x1)|), n = `splits` when x1
// is the split vertex, else 1. `to_x2` is the unit direction x1 -> x2. 0 (no light connection could produce
// the path) when the density or the cosine is 0.
inline float connection_factor(std::uint32_t connections, std::uint32_t splits, const glm::vec3& x1,
                               float bsdf_pdf_x1, const glm::vec3& x2, const glm::vec3& n2, const glm::vec3& to_x2) {
  const float cos2 = std::abs(glm::dot(n2, to_x2));
  const glm::vec3 d = x2 - x1;
  const float denom = std::numbers::pi_v<float> * bsdf_pdf_x1 * cos2 * static_cast<float>(splits);
  if (!(denom > 0.0f)) return 0.0f;
  const float f = static_cast<float>(connections) * glm::dot(d, d) / denom;
  return std::isfinite(f) ? f : 0.0f;
}

// A light subpath's first hit x2, ready for connections: everything about it that does not depend on the camera
// vertex, computed once and reused by every connection made to it (up to 1 + 2 K per camera sample).
struct LightVertex {
  SurfacePoint x2;        // non-delta
  glm::vec3 target{0.0f};  // leaving_origin(x2): the connections' shadow rays end there
  glm::vec3 weight{0.0f};  // the emission sample's weight, pi Le / pE
  // With n p(x2) factored out of A and B (top of the file): x2's BSDF density toward x3 given wo toward x1,
  // which for a Lambertian x2 is |cos(n2, x2 -> x3)| / pi whichever side x1 is on (a connection that
  // contributes has x1 on x3's side); the light sampler's density of x3 from x2; and C itself.
  float continue_pdf = 0.0f;
  float light_sample_pdf = 0.0f;
  float connection_pdf = 0.0f;
};

// The light vertex of a light subpath that starts at `emission` and first hits the non-delta point `x2`.
inline LightVertex make_light_vertex(const SceneContext& ctx, const EmissionSample& emission, const SurfacePoint& x2,
                                     std::uint32_t connections) {
  LightVertex lv;
  lv.x2 = x2;
  lv.target = leaving_origin(x2);
  lv.weight = emission.weight;
  const float cos2_to_x3 = std::abs(glm::dot(x2.ng, x2.wo));
  lv.continue_pdf = cos2_to_x3 * std::numbers::inv_pi_v<float>;
  lv.light_sample_pdf = ctx.lights->pdf_light(emission.light, x2.p, emission.point, emission.normal);
  lv.connection_pdf = static_cast<float>(connections) * emission.pdf_area * cos2_to_x3 * std::numbers::inv_pi_v<float>;
  return lv;
}

// One light connection: the camera vertex x1 (throughput `beta_camera` up to it, `x1_origin` =
// leaving_origin(x1), where the shadow ray starts: a connection that contributes leaves x1 on wo's side) and
// the light vertex, ready for the shadow ray between them. False when it cannot contribute. The contribution
// is beta_camera f1 |cos1| f2 |cos2| / d12^2 * emission.weight / M, weighted by the power heuristic above
// (n = `splits`: the path tracer's continuations from x1, M = connections).
inline bool prepare_light_connection(const SurfacePoint& x1, const glm::vec3& x1_origin, const glm::vec3& beta_camera,
                                     const LightVertex& lv, std::uint32_t connections, std::uint32_t splits,
                                     ShadowQuery& out) {
  const SurfacePoint& x2 = lv.x2;
  const glm::vec3 d = x2.p - x1.p;
  const float dist2 = glm::dot(d, d);
  if (!(dist2 > 0.0f)) return false;
  const float inv_dist = 1.0f / std::sqrt(dist2);
  const glm::vec3 to_x2 = d * inv_dist;
  float pdf_x1 = 0.0f;
  const glm::vec3 f1 = x1.bsdf().eval(x1.wo, to_x2, x1.ng, pdf_x1);  // f1 |cos(n1, x1 -> x2)|
  if (!(max_component(f1) > 0.0f)) return false;
  // x2's BSDF with the roles exchanged: light arrives from x3 (x2.wo) and leaves toward x1, so eval(x2.wo,
  // -to_x2) = f2 |cos(n2, x2 -> x1)|, the cosine the connection needs. Only non-delta (Lambertian) BSDFs get
  // here, and theirs is symmetric in its two directions, one-sided rule included (both on the front). f2 > 0
  // also puts x1 on x3's side of x2, where lv.continue_pdf and lv.target hold.
  const glm::vec3 f2 = x2.bsdf().eval(x2.wo, -to_x2, x2.ng);
  if (!(max_component(f2) > 0.0f)) return false;

  // The three strategies' densities (see the top of the file).
  const float cos2_to_x1 = std::abs(glm::dot(x2.ng, to_x2));
  const float p_x2 = pdf_x1 * cos2_to_x1 / dist2;
  const float k = static_cast<float>(splits);
  const float a = k * p_x2 * lv.continue_pdf;
  const float b = k * p_x2 * lv.light_sample_pdf;
  const float weight = power_heuristic3(lv.connection_pdf, a, b);
  if (!(weight > 0.0f)) return false;

  Ray& shadow = out.ray;
  shadow.org = x1_origin;
  if (!aim_shadow_ray(shadow, lv.target)) return false;
  out.contribution = beta_camera * f1 * f2 * lv.weight * (weight / (dist2 * static_cast<float>(connections)));
  return std::isfinite(out.contribution.x) && std::isfinite(out.contribution.y) && std::isfinite(out.contribution.z);
}

}  // namespace twinray
