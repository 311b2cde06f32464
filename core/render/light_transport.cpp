#include "core/render/light_transport.h"

#include "core/intersect/sphere_robust.h"

#include "core/geometry/ray_offset.h"
#include "core/sampling/warp.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace twinray {

SceneContext SceneContext::make(const Scene& scene, const Backend& backend, const EnvironmentLight* environment,
                                const LightSampler* lights) {
  SceneContext ctx;
  ctx.scene = &scene;
  ctx.backend = &backend;
  ctx.environment = environment;
  ctx.lights = (lights != nullptr && !lights->empty()) ? lights : nullptr;
  const std::uint32_t end = scene.geometry.geom_id_end();
  ctx.bsdf_of_geom.resize(end);
  ctx.shape_of_geom.resize(end);
  for (std::uint32_t id = 0; id < end && id < scene.shapes.size(); ++id)
    ctx.bsdf_of_geom[id] = Bsdf::from_material(scene.material_of(id));
  for (std::size_t i = 0; i < scene.geometry.meshes.size(); ++i)
    ctx.shape_of_geom[scene.geometry.meshes[i].geom_id] = {false, static_cast<std::uint32_t>(i)};
  for (std::size_t i = 0; i < scene.geometry.spheres.size(); ++i)
    ctx.shape_of_geom[scene.geometry.spheres[i].geom_id] = {true, static_cast<std::uint32_t>(i)};
  return ctx;
}

SurfacePoint make_surface_point(const SceneContext& ctx, const Ray& ray, const Hit& hit) {
  SurfacePoint sp;
  sp.ng = hit.ng;
  sp.wo = -glm::normalize(ray.dir);
  const SceneContext::ShapeRef ref = ctx.shape_of_geom[hit.geom_id];
  if (ref.sphere) {
    const Sphere& s = ctx.scene->geometry.spheres[ref.index];
    // In double and rounded once (sphere_robust.h): center + radius * ng in float is off by ulps of the
    // center and the radius, enough to start secondary rays inside a large sphere.
    sp.p = sphere_hit_point(ray.org, ray.dir, hit.t, s.center, s.radius);
  } else {
    const TriangleMesh& m = ctx.scene->geometry.meshes[ref.index];
    const glm::uvec3 tri = m.indices[hit.prim_id];
    const glm::vec3 &p0 = m.positions[tri.x], &p1 = m.positions[tri.y], &p2 = m.positions[tri.z];
    sp.p = (1.0f - hit.u - hit.v) * p0 + hit.u * p1 + hit.v * p2;
    // The barycentric point and the triangle test err by ulps of the vertices, which may be far larger
    // than the point's own coordinates.
    const glm::vec3 m3 = glm::max(glm::abs(p0), glm::max(glm::abs(p1), glm::abs(p2)));
    sp.error_scale = std::max(m3.x, std::max(m3.y, m3.z));
  }
  sp.material = &ctx.scene->material_of(hit.geom_id);
  sp.bsdf = &ctx.bsdf_of_geom[hit.geom_id];
  return sp;
}

void record_first_hit(FirstHitInfo* first, const SurfacePoint& sp, float t) {
  if (first == nullptr) return;
  first->hit = true;
  first->normal = glm::dot(sp.ng, sp.wo) >= 0.0f ? sp.ng : -sp.ng;
  first->albedo = sp.bsdf->albedo();
  first->depth = t;
}

Ray spawn_ray(const SurfacePoint& sp, const glm::vec3& dir) {
  Ray r;
  r.org = offset_ray_origin(sp.p, glm::dot(dir, sp.ng) > 0.0f ? sp.ng : -sp.ng, sp.error_scale);
  r.dir = dir;
  r.tmin = 0.0f;
  r.tmax = std::numeric_limits<float>::infinity();
  return r;
}

float emission_weight(SamplingStrategy strategy, bool prev_delta, float bsdf_pdf, float light_pdf) {
  if (prev_delta || !(light_pdf > 0.0f)) return 1.0f;  // no light sample could have produced this path
  switch (strategy) {
    case SamplingStrategy::Mis: return power_heuristic(1.0f, bsdf_pdf, 1.0f, light_pdf);
    case SamplingStrategy::Bsdf: return 1.0f;
    case SamplingStrategy::Light: return 0.0f;
  }
  return 1.0f;
}

glm::vec3 sample_direct_light(const SceneContext& ctx, const SurfacePoint& sp, SamplingStrategy strategy,
                              Sampler& sampler, TraceCounters& counters) {
  if (ctx.lights == nullptr || strategy == SamplingStrategy::Bsdf) return glm::vec3(0.0f);
  const std::optional<LightSample> ls = ctx.lights->sample(sp.p, sampler.next_2d());
  if (!ls || max_component(ls->radiance) <= 0.0f) return glm::vec3(0.0f);
  const glm::vec3 f = sp.bsdf->eval(sp.wo, ls->wi, sp.ng);
  if (max_component(f) <= 0.0f) return glm::vec3(0.0f);

  Ray shadow;
  if (ls->is_environment) {
    shadow = spawn_ray(sp, ls->wi);
  } else {
    shadow.org = offset_ray_origin(sp.p, glm::dot(ls->wi, sp.ng) > 0.0f ? sp.ng : -sp.ng, sp.error_scale);
    const glm::vec3 target =
        offset_ray_origin(ls->point, glm::dot(ls->wi, ls->normal) < 0.0f ? ls->normal : -ls->normal);
    const glm::vec3 d = target - shadow.org;
    const float dist = glm::length(d);
    if (!(dist > 0.0f)) return glm::vec3(0.0f);
    shadow.dir = d / dist;
    shadow.tmin = 0.0f;
    shadow.tmax = dist * (1.0f - kShadowRayShortening);
  }
  ++counters.shadow_rays;
  if (ctx.backend->occluded(shadow, counters.query_stats())) return glm::vec3(0.0f);

  const float weight = strategy == SamplingStrategy::Mis
                           ? power_heuristic(1.0f, ls->pdf, 1.0f, sp.bsdf->pdf(sp.wo, ls->wi, sp.ng))
                           : 1.0f;
  return f * ls->radiance * (weight / ls->pdf);
}

glm::vec3 escaped_radiance(const SceneContext& ctx, const glm::vec3& dir, SamplingStrategy strategy,
                           bool prev_delta, float prev_bsdf_pdf) {
  if (ctx.environment == nullptr) return glm::vec3(0.0f);
  const glm::vec3 le = ctx.environment->eval(dir);
  if (prev_delta || ctx.lights == nullptr) return le;
  return le * emission_weight(strategy, prev_delta, prev_bsdf_pdf, ctx.lights->pdf_environment(dir));
}

glm::vec3 surface_emission(const SceneContext& ctx, const SurfacePoint& sp, const Hit& hit,
                           SamplingStrategy strategy, bool prev_delta, float prev_bsdf_pdf,
                           const glm::vec3& prev_p) {
  const glm::vec3 le = emitted_radiance(*sp.material, sp.ng, sp.wo);
  if (max_component(le) <= 0.0f) return glm::vec3(0.0f);
  if (prev_delta || ctx.lights == nullptr) return le;
  return le * emission_weight(strategy, prev_delta, prev_bsdf_pdf, ctx.lights->pdf_surface(prev_p, hit, sp.p));
}

}  // namespace twinray
