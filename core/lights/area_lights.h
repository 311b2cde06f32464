#pragma once
// Light sources the integrators sample explicitly: emissive triangles, emissive spheres, and the
// environment, chosen in proportion to their emitted power.
//
// Emission is one-sided: a surface emits its radiance only toward the side its geometric normal points
// to (triangles: the counter-clockwise front; spheres: outward).
//
// Sampling strategies (densities are with respect to solid angle at the receiving point `ref`):
//  - triangle: a point uniform in area, pdf = d^2 / (|cos_light| area);
//  - sphere seen from outside: a direction uniform in the cone the sphere subtends, pdf = 1 / (2 pi (1 -
//    cos_max)) -- every such direction hits the sphere, and no sample is wasted on its far side;
//  - sphere seen from inside (or from its surface): a point uniform in area, as for triangles;
//  - environment: EnvironmentLight::sample (importance tables, or uniform directions).
// The choice of light uses a Distribution1D: surface lights in proportion to their power (pi * area *
// luminance(radiance)). The environment, when there are surface lights too, gets a fixed half of the
// choices: its "power" has no robust estimate (pi R^2 4 pi L with R the scene's bounding radius lets one
// large ground sphere starve a small lamp of samples), and a fixed half is never worse than twice the
// variance of the best split in either extreme (environment or lamps dominating). pdf_* functions return
// exactly the density sample() produced, selection included, which is what the MIS weights need.
//
// Spheres only enter this code when the scene has emissive spheres; the environment only when there is one.

#include "core/geometry/hit.h"
#include "core/lights/environment_light.h"
#include "core/sampling/distribution_1d.h"
#include "core/sampling/warp.h"
#include "core/scene/scene.h"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

namespace twinray {

// Radiance an emissive surface sends toward `toward` (unit, pointing away from the surface), given the
// surface's geometric normal. Zero on the back side and for non-emissive materials.
inline glm::vec3 emitted_radiance(const Material& m, const glm::vec3& ng, const glm::vec3& toward) {
  if (m.type != MaterialType::Emissive) return glm::vec3(0.0f);
  return ng.x * toward.x + ng.y * toward.y + ng.z * toward.z > 0.0f ? m.radiance : glm::vec3(0.0f);
}

struct EmissiveTriangle {
  glm::vec3 p0{0.0f}, e1{0.0f}, e2{0.0f};  // p = p0 + b1 e1 + b2 e2
  glm::vec3 normal{0.0f};                  // unit geometric normal, cross(e1, e2) direction
  float area = 0.0f;
  glm::vec3 radiance{0.0f};
};

struct EmissiveSphere {
  glm::vec3 center{0.0f};
  float radius = 0.0f;
  glm::vec3 radiance{0.0f};
};

struct LightSample {
  glm::vec3 wi{0.0f};        // unit direction from ref toward the light
  glm::vec3 point{0.0f};     // the sampled point on a surface light (unused for the environment)
  glm::vec3 normal{0.0f};    // its unit geometric normal
  glm::vec3 radiance{0.0f};  // radiance arriving at ref along -wi if unoccluded (0 on back sides)
  float pdf = 0.0f;          // solid angle at ref, light selection included
  bool is_environment = false;
  std::uint32_t light = 0;   // the light's index in sample order (triangles, spheres, environment)
};

// A point on a surface light and a direction leaving its emitting side: the start of a light path
// (LightSampler::sample_emission).
struct EmissionSample {
  glm::vec3 point{0.0f};
  glm::vec3 normal{0.0f};    // unit, the emitting side
  glm::vec3 dir{0.0f};       // unit, cosine-distributed about `normal`
  glm::vec3 weight{0.0f};    // Le |cos| / (pdf_area pdf_dir) = pi Le / pdf_area, light selection included
  float error_scale = 0.0f;  // magnitude of the coordinates the point's error comes from (ray_offset.h)
  std::uint32_t light = 0;   // the light's index in sample order
  float pdf_area = 0.0f;     // area density of `point`, light selection included (emission_pdf_area(light))
};

class LightSampler {
 public:
  // `env` may be null; it must outlive the sampler. Lights with zero radiance are ignored.
  LightSampler(const Scene& scene, const EnvironmentLight* env);

  bool empty() const { return !selection_.has_value(); }
  std::size_t triangle_count() const { return triangles_.size(); }
  std::size_t sphere_count() const { return spheres_.size(); }
  bool has_environment() const { return env_ != nullptr && env_index_ != kNone; }

  // A light sample for receiving point `ref`. u_select picks the light, u the point on it.
  std::optional<LightSample> sample(const glm::vec3& ref, float u_select, glm::vec2 u) const;
  // The same from one 2D value: u.x picks the light and, rescaled to [0, 1) within the chosen light's share
  // of [0, 1), becomes the first coordinate of the point on it. Stratified values then stay stratified over
  // the union of the lights (a quad lamp made of two triangles is sampled like one square) instead of each
  // light receiving a random subset of them; what the integrators use with the Sobol sampler.
  std::optional<LightSample> sample(const glm::vec3& ref, glm::vec2 u) const;
  // The same without the optional (what the integrators call once per vertex): false when the sample
  // cannot contribute (pdf 0 or not finite), `out` then unspecified.
  bool sample(const glm::vec3& ref, glm::vec2 u, LightSample& out) const;

  // Whether any surface (triangle or sphere) light exists: only those start light paths.
  bool has_surface_lights() const { return selection_.has_value() && surface_fraction_ > 0.0f; }
  // The start of a light path: a surface light chosen in proportion to its power as sample() chooses
  // (u_point.x, renormalised over the surface lights: the environment never starts a light path), a point
  // uniform in its area (u_point), and a cosine-weighted direction on its emitting side (u_dir). False when
  // nothing can be emitted (no surface light, a zero-area pick).
  bool sample_emission(glm::vec2 u_point, glm::vec2 u_dir, EmissionSample& out) const;

  // Density with which sample(ref, ...) would produce the direction toward `point` on surface light hit
  // `hit` (geometry and primitive ids); 0 when that primitive is not a sampled light.
  float pdf_surface(const glm::vec3& ref, const Hit& hit, const glm::vec3& point) const;
  // Density with which sample() would produce direction `dir` toward the environment.
  float pdf_environment(const glm::vec3& dir) const;
  // Density (solid angle at `ref`) with which sample(ref, ...) would produce the point `point` (unit
  // geometric normal `normal`) on light `light_index`; 0 for the environment or a light never chosen.
  float pdf_light(std::size_t light_index, const glm::vec3& ref, const glm::vec3& point, const glm::vec3& normal) const;
  // Area density with which sample_emission() starts a light path at a point of light `light_index` (selection
  // included; 0 for the environment and for lights never chosen), and the same for the light hit `hit`.
  float emission_pdf_area(std::size_t light_index) const {
    return light_index < emission_pdf_area_.size() ? emission_pdf_area_[light_index] : 0.0f;
  }
  float emission_pdf_area(const Hit& hit) const;

  // Probability of choosing each light, in sample order: triangles, spheres, environment (for tests).
  float selection_probability(std::size_t light_index) const;
  const std::vector<EmissiveTriangle>& triangles() const { return triangles_; }
  const std::vector<EmissiveSphere>& spheres() const { return spheres_; }

 private:
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

  // The light u picks (as sample(ref, u) picks it), its probability, and u rescaled to [0, 1) within the
  // light's share.
  std::size_t select_light(float u, float& pmf, float& rest) const;
  bool sample_light(std::size_t i, float pmf, const glm::vec3& ref, glm::vec2 u, LightSample& s) const;
  static void sample_triangle(const EmissiveTriangle& tri, const glm::vec3& ref, glm::vec2 u, LightSample& s);
  static void sample_sphere(const EmissiveSphere& sph, const glm::vec3& ref, glm::vec2 u, LightSample& s);
  static float sphere_pdf(const EmissiveSphere& sph, const glm::vec3& ref, const glm::vec3& point,
                          const glm::vec3& normal);

  std::vector<EmissiveTriangle> triangles_;
  std::vector<EmissiveSphere> spheres_;
  // Per geometry id: index of the shape's first light in sample order (kNone when it emits nothing).
  std::vector<std::uint32_t> first_light_of_geom_;
  const EnvironmentLight* env_ = nullptr;
  std::uint32_t env_index_ = kNone;
  std::optional<Distribution1D> selection_;
  // The selection again, in float, for the common case of a few lights: the index is the number of CDF
  // steps at or below u (no branch, no search), the remapped u is (u - cdf) * inv_width. pmf_ is the
  // selection probability of each light (pdf_surface needs it for every emitter hit).
  static constexpr std::size_t kFewLights = 16;
  std::vector<float> cdf_;        // size n + 1, only when n <= kFewLights
  std::vector<float> inv_width_;  // 1 / (cdf[i+1] - cdf[i]), 0 for empty bins; only when n <= kFewLights
  std::vector<float> pmf_;        // size n
  float surface_fraction_ = 0.0f; // probability that sample() picks a surface light (1 without environment)
  std::vector<float> emission_pdf_area_;  // per light: pmf / surface_fraction / area (0: environment, unused)
};

// The light sample of every path vertex, defined here and forced inline so that it compiles into the path
// integrator's loop: 2.2% fewer instructions of the Cornell box render than calls into area_lights.cpp
// (callgrind; docs/rendering.md). Spheres and the environment stay out of line.
[[gnu::always_inline]] inline bool LightSampler::sample(const glm::vec3& ref, glm::vec2 u, LightSample& s) const {
  if (!selection_) return false;
  float pmf = 0.0f, rest = 0.0f;
  const std::size_t i = select_light(u.x, pmf, rest);
  return sample_light(i, pmf, ref, glm::vec2(rest, u.y), s);
}

[[gnu::always_inline]] inline std::size_t LightSampler::select_light(float u, float& pmf, float& rest) const {
  if (cdf_.empty()) return selection_->sample_discrete(u, &pmf, &rest);
  // Empty bins (zero power) have cdf[i] == cdf[i+1]: both steps are counted or neither, so they are
  // skipped; u < 1 = cdf[n] never counts the last step.
  const std::size_t n = pmf_.size();
  std::size_t i = 0;
  for (std::size_t k = 1; k < n; ++k) i += u >= cdf_[k] ? 1 : 0;
  pmf = pmf_[i];
  rest = std::max(std::min((u - cdf_[i]) * inv_width_[i], 0x1.fffffep-1f), 0.0f);
  return i;
}

[[gnu::always_inline]] inline bool LightSampler::sample_light(std::size_t i, float pmf, const glm::vec3& ref,
                                                           glm::vec2 u, LightSample& s) const {
  if (!(pmf > 0.0f)) return false;
  s = LightSample{};
  if (i < triangles_.size()) {
    sample_triangle(triangles_[i], ref, u, s);
  } else if (i - triangles_.size() < spheres_.size()) {
    sample_sphere(spheres_[i - triangles_.size()], ref, u, s);
  } else {
    const EnvironmentLight::Sample es = env_->sample(u);
    s.wi = es.dir;
    s.radiance = es.radiance;
    s.pdf = es.pdf;
    s.is_environment = true;
  }
  s.pdf *= pmf;
  s.light = static_cast<std::uint32_t>(i);
  return s.pdf > 0.0f && std::isfinite(s.pdf);
}

[[gnu::always_inline]] inline void LightSampler::sample_triangle(const EmissiveTriangle& tri, const glm::vec3& ref,
                                                              glm::vec2 u, LightSample& s) {
  const glm::vec3 b = sample_uniform_triangle(u);
  s.point = tri.p0 + b.y * tri.e1 + b.z * tri.e2;
  s.normal = tri.normal;
  const glm::vec3 d = s.point - ref;
  const float dist2 = glm::dot(d, d);
  if (!(dist2 > 0.0f)) return;  // pdf 0: rejected by the caller
  s.wi = d / std::sqrt(dist2);
  const float cos_light = -glm::dot(s.normal, s.wi);
  if (!(cos_light > 0.0f)) return;  // back side (one-sided emission) or edge-on: no contribution
  s.radiance = tri.radiance;
  s.pdf = dist2 / (cos_light * tri.area);
}

}  // namespace twinray
