#pragma once
// Building blocks both integrators use: the surface point of a hit, spawning rays off surfaces, light
// sampling with its MIS weight, and the weight of emission found by BSDF sampling.
//
// Ray spawning (no global epsilon anywhere):
//  - A ray leaving a surface starts at offset_ray_origin(p, n) (Wächter-Binder, core/geometry/ray_offset.h)
//    with n the geometric normal flipped to the side the ray leaves into, and tmin = 0. The offset scales
//    with the magnitude of p, so it works for 0.1-unit and 35-unit scenes alike.
//  - A shadow ray toward a point on a surface light ends at that point offset the same way toward the
//    receiver, so the light's own surface lies beyond the end of the segment. tmax is in addition shortened
//    by the relative factor kShadowRayShortening (1e-4): that absorbs the rounding of normalising the
//    direction and of the length (a few ulps), with wide margin, and never reaches a real occluder unless it
//    lies within 1e-4 of the distance from the light's surface (0.35 mm in a 35-unit scene).
//  - A shadow ray toward the environment has tmax = +inf.
// The hit point itself is recomputed from barycentrics (triangles) or from centre + radius * normal
// (spheres) rather than taken as org + t dir: its error is then relative to the vertex coordinates, which
// is the error model the Wächter-Binder offset is built for, however long the ray was.

#include "core/render/integrator.h"

#include <glm/vec3.hpp>

namespace twinray {

inline constexpr float kShadowRayShortening = 1e-4f;

struct SurfacePoint {
  glm::vec3 p{0.0f};
  glm::vec3 ng{0.0f};  // unit geometric normal, as reported (never flipped)
  glm::vec3 wo{0.0f};  // unit, toward where the ray came from
  float error_scale = 0.0f;  // magnitude of the coordinates p's error comes from (ray_offset.h); 0: p's own
  const Material* material = nullptr;
  const Bsdf* bsdf = nullptr;
};

SurfacePoint make_surface_point(const SceneContext& ctx, const Ray& ray, const Hit& hit);

// Fills the auxiliary first-hit record (normal facing the viewer, albedo, depth) at the camera ray's hit.
void record_first_hit(FirstHitInfo* first, const SurfacePoint& sp, float t);

// A ray leaving p along unit direction dir, offset to the side of ng that dir points into.
// A ray leaving the surface point in direction dir, its origin offset to dir's side (ray_offset.h).
Ray spawn_ray(const SurfacePoint& sp, const glm::vec3& dir);

// The MIS weight of emission reached by a BSDF-sampled ray (or by the camera ray: prev_delta = true),
// given the BSDF's density for that direction and the light sampler's density for the same direction.
float emission_weight(SamplingStrategy strategy, bool prev_delta, float bsdf_pdf, float light_pdf);

// One light sample at a non-delta surface point: BSDF * radiance / pdf, MIS weighted against BSDF
// sampling for the Mis strategy. Traces one shadow ray when the sample can contribute.
glm::vec3 sample_direct_light(const SceneContext& ctx, const SurfacePoint& sp, SamplingStrategy strategy,
                              Sampler& sampler, TraceCounters& counters);

// Radiance arriving from outside the scene along unit direction dir, weighted for MIS.
glm::vec3 escaped_radiance(const SceneContext& ctx, const glm::vec3& dir, SamplingStrategy strategy,
                           bool prev_delta, float prev_bsdf_pdf);

// Emission of the surface at `sp` toward the previous vertex, weighted for MIS.
glm::vec3 surface_emission(const SceneContext& ctx, const SurfacePoint& sp, const Hit& hit,
                           SamplingStrategy strategy, bool prev_delta, float prev_bsdf_pdf,
                           const glm::vec3& prev_p);

inline float max_component(const glm::vec3& v) { return std::max(v.x, std::max(v.y, v.z)); }

}  // namespace twinray
