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
// The hit point itself is rebuilt from barycentrics (triangles: those of org + t dir, clamped to the
// triangle, triangle_surface.h) or from centre + radius * normal (spheres) rather than taken as org + t dir:
// its error is then relative to the vertex coordinates, which is the error model the Wächter-Binder offset
// is built for, however long the ray was.

#include "core/render/integrator.h"

#include "core/geometry/ray_offset.h"
#include "core/intersect/sphere_robust.h"
#include "core/lights/area_lights.h"
#include "core/sampling/warp.h"

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace twinray {

inline constexpr float kShadowRayShortening = 1e-4f;

inline float max_component(const glm::vec3& v) { return std::max(v.x, std::max(v.y, v.z)); }

// The power heuristic over three strategies: own^2 / (own^2 + a^2 + b^2), each density already times its
// sample count (light connections, core/render/light_connection.h).
inline float power_heuristic3(float own, float a, float b) {
  if (std::isinf(own)) return std::isinf(a) || std::isinf(b) ? 0.0f : 1.0f;
  if (!(own > 0.0f)) return 0.0f;
  const float ra = a / own, rb = b / own;
  return 1.0f / (1.0f + ra * ra + rb * rb);
}

struct SurfacePoint {
  glm::vec3 p{0.0f};
  glm::vec3 ng{0.0f};  // unit geometric normal, as reported (never flipped)
  glm::vec3 wo{0.0f};  // unit, toward where the ray came from
  float error_scale = 0.0f;  // magnitude of the coordinates p's error comes from (ray_offset.h); 0: p's own
  const GeomShading* geom = nullptr;

  const Bsdf& bsdf() const { return geom->bsdf; }
};

// The surface point of `hit` on `ray`, whose direction must be unit length (camera rays and every ray the
// integrators spawn are): wo is then -dir without a normalisation. Reads t and the ids of the hit only, so
// it takes the answer of Backend::intersect_ids: triangles from SceneContext::triangles (triangle_surface.h),
// spheres from the double-precision root (sphere_robust.h), each with the normal a full closest-hit query
// would have reported.
[[gnu::always_inline]] inline SurfacePoint make_surface_point(const SceneContext& ctx, const Ray& ray, const Hit& hit) {
  SurfacePoint sp;
  sp.wo = -ray.dir;
  sp.geom = &ctx.geoms[hit.geom_id];
  if (sp.geom->sphere) {
    const Sphere& s = ctx.scene->geometry.spheres[sp.geom->shape];
    // In double and rounded once (sphere_robust.h): center + radius * ng in float is off by ulps of the
    // center and the radius, enough to start secondary rays inside a large sphere.
    sphere_hit_point_and_normal(ray.org, ray.dir, hit.t, s.center, s.radius, sp.p, sp.ng);
  } else {
    const TriangleSurface& tri = ctx.triangles[sp.geom->first_triangle + hit.prim_id];
    sp.p = tri.point(ray, hit.t);
    sp.ng = tri.ng;
    // The point errs by ulps of the vertices, which may be far larger than its own coordinates.
    sp.error_scale = tri.error_scale;
  }
  return sp;
}

// Fills the auxiliary first-hit record (normal facing the viewer, albedo, depth) at the camera ray's hit.
void record_first_hit(FirstHitInfo* first, const SurfacePoint& sp, float t);

// A ray leaving the surface point in direction dir, its origin offset to dir's side (ray_offset.h).
inline Ray spawn_ray(const SurfacePoint& sp, const glm::vec3& dir) {
  Ray r;
  r.org = offset_ray_origin(sp.p, glm::dot(dir, sp.ng) > 0.0f ? sp.ng : -sp.ng, sp.error_scale);
  r.dir = dir;
  r.tmin = 0.0f;
  r.tmax = std::numeric_limits<float>::infinity();
  return r;
}

// Where every ray leaving the non-delta surface point `sp` starts: offset to wo's side. Non-delta BSDFs
// (Lambertian) scatter only to the side wo is on (a sample or an evaluation toward the other side is 0), so
// a vertex's light sample, its light connections and its continuation all leave from this one point, the
// same bits spawn_ray gives for their directions; the path integrator computes it once per vertex (about 3%
// of the Cornell box's instructions went to computing it up to three times, docs/rendering.md).
inline glm::vec3 leaving_origin(const SurfacePoint& sp) {
  return offset_ray_origin(sp.p, glm::dot(sp.wo, sp.ng) > 0.0f ? sp.ng : -sp.ng, sp.error_scale);
}

// The MIS weight of emission reached by a BSDF-sampled ray (or by the camera ray: prev_delta = true),
// given the BSDF's density for that direction and the light sampler's density for the same direction.
float emission_weight(SamplingStrategy strategy, bool prev_delta, float bsdf_pdf, float light_pdf);

// A light sample waiting for its shadow ray: what it adds when the ray is unoccluded.
struct ShadowQuery {
  Ray ray;
  glm::vec3 contribution{0.0f};  // BSDF * radiance / pdf, MIS weighted
};

// Aims `shadow`, whose origin is set, at `target` (both already offset off their surfaces): unit direction, and
// tmax short of the target by kShadowRayShortening so that the far end's own surface is not hit. False when
// the two points coincide (nothing to trace).
inline bool aim_shadow_ray(Ray& shadow, const glm::vec3& target) {
  const glm::vec3 d = target - shadow.org;
  const float dist2 = glm::dot(d, d);
  if (!(dist2 > 0.0f)) return false;
  const float inv_dist = 1.0f / std::sqrt(dist2);
  shadow.dir = d * inv_dist;
  shadow.tmin = 0.0f;
  shadow.tmax = dist2 * inv_dist * (1.0f - kShadowRayShortening);
  return true;
}

// One light sample at a non-delta surface point, up to its shadow ray: false when the sample cannot
// contribute (nothing to trace). The contribution is BSDF * radiance / pdf, MIS weighted against BSDF
// sampling for the Mis strategy. `u` is the sampler's 2D value for the light choice and the point on it.
// Defined here so that the path integrator's wavefront loop inlines it: 1.2% fewer instructions of the render
// than a call per light sample (callgrind, Cornell box).
// `connection_factor` > 0 (light connections, core/render/light_connection.h): the vertex is a camera path's
// x2 and the light connection strategy competes too, with C / (K p(x2)) = connection_factor * pE |cos(n2, wi)|.
// `origin` is leaving_origin(sp).
[[gnu::always_inline]] inline bool prepare_direct_light(const SceneContext& ctx, const SurfacePoint& sp,
                                                       const glm::vec3& origin, SamplingStrategy strategy,
                                                       glm::vec2 u, ShadowQuery& out, float connection_factor = 0.0f) {
  if (ctx.lights == nullptr || strategy == SamplingStrategy::Bsdf) return false;
  LightSample ls;
  if (!ctx.lights->sample(sp.p, u, ls) || max_component(ls.radiance) <= 0.0f) return false;
  float bsdf_pdf = 0.0f;
  const glm::vec3 f = sp.bsdf().eval(sp.wo, ls.wi, sp.ng, bsdf_pdf);
  if (max_component(f) <= 0.0f) return false;

  // f > 0: ls.wi is on wo's side, so the shadow ray leaves from `origin`.
  Ray& shadow = out.ray;
  shadow.org = origin;
  if (ls.is_environment) {
    shadow.dir = ls.wi;
    shadow.tmin = 0.0f;
    shadow.tmax = std::numeric_limits<float>::infinity();
  } else {
    const glm::vec3 target =
        offset_ray_origin(ls.point, glm::dot(ls.wi, ls.normal) < 0.0f ? ls.normal : -ls.normal);
    if (!aim_shadow_ray(shadow, target)) return false;
  }
  float weight = 1.0f;
  if (strategy == SamplingStrategy::Mis) {
    if (connection_factor > 0.0f) {
      const float c = connection_factor * ctx.lights->emission_pdf_area(ls.light) * std::abs(glm::dot(sp.ng, ls.wi));
      weight = power_heuristic3(ls.pdf, bsdf_pdf, c);
    } else {
      weight = power_heuristic(1.0f, ls.pdf, 1.0f, bsdf_pdf);
    }
  }
  out.contribution = f * ls.radiance * (weight / ls.pdf);
  return true;
}

// prepare_direct_light and its shadow ray: the light sample's contribution, 0 when occluded.
glm::vec3 sample_direct_light(const SceneContext& ctx, const SurfacePoint& sp, SamplingStrategy strategy,
                              glm::vec2 u, TraceCounters& counters);

// Radiance arriving from outside the scene along unit direction dir, weighted for MIS.
glm::vec3 escaped_radiance(const SceneContext& ctx, const glm::vec3& dir, SamplingStrategy strategy,
                           bool prev_delta, float prev_bsdf_pdf);

// Emission of the surface at `sp` toward the previous vertex, weighted for MIS. Zero unless the surface
// emits and `sp.wo` is on its front side. `connection_factor` > 0: the previous vertex is a camera path's x2
// and light connections compete (core/render/light_connection.h), the factor already times |cos(n2, wi)|.
glm::vec3 weighted_surface_emission(const SceneContext& ctx, const SurfacePoint& sp, const Hit& hit,
                                    SamplingStrategy strategy, bool prev_delta, float prev_bsdf_pdf,
                                    const glm::vec3& prev_p, float connection_factor = 0.0f);
inline glm::vec3 surface_emission(const SceneContext& ctx, const SurfacePoint& sp, const Hit& hit,
                                  SamplingStrategy strategy, bool prev_delta, float prev_bsdf_pdf,
                                  const glm::vec3& prev_p, float connection_factor = 0.0f) {
  if (!sp.geom->emissive || !(glm::dot(sp.ng, sp.wo) > 0.0f)) return glm::vec3(0.0f);
  return weighted_surface_emission(ctx, sp, hit, strategy, prev_delta, prev_bsdf_pdf, prev_p, connection_factor);
}


}  // namespace twinray
