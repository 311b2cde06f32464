#include "core/render/light_transport.h"

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
  ctx.geoms.resize(end);
  for (std::uint32_t id = 0; id < end && id < scene.shapes.size(); ++id) {
    const Material& m = scene.material_of(id);
    GeomShading& g = ctx.geoms[id];
    g.bsdf = Bsdf::from_material(m);
    g.emissive = m.type == MaterialType::Emissive;
    g.emission = g.emissive ? m.radiance : glm::vec3(0.0f);
  }
  std::size_t triangle_count = 0;
  for (const TriangleMesh& m : scene.geometry.meshes) triangle_count += m.triangle_count();
  ctx.triangles.reserve(triangle_count);
  for (std::size_t i = 0; i < scene.geometry.meshes.size(); ++i) {
    const TriangleMesh& m = scene.geometry.meshes[i];
    GeomShading& g = ctx.geoms[m.geom_id];
    g.sphere = false;
    g.shape = static_cast<std::uint32_t>(i);
    g.first_triangle = static_cast<std::uint32_t>(ctx.triangles.size());
    for (const glm::uvec3& tri : m.indices)
      ctx.triangles.push_back(TriangleSurface::make(m.positions[tri.x], m.positions[tri.y], m.positions[tri.z]));
  }
  for (std::size_t i = 0; i < scene.geometry.spheres.size(); ++i) {
    GeomShading& g = ctx.geoms[scene.geometry.spheres[i].geom_id];
    g.sphere = true;
    g.shape = static_cast<std::uint32_t>(i);
  }
  return ctx;
}

void Integrator::radiance(std::span<CameraSample> samples, std::span<glm::vec3> out, std::span<FirstHitInfo> first,
                          TraceCounters& counters) const {
  for (std::size_t i = 0; i < samples.size(); ++i)
    out[i] = radiance(samples[i].ray, samples[i].sampler, counters, first.empty() ? nullptr : &first[i]);
}

void record_first_hit(FirstHitInfo* first, const SurfacePoint& sp, float t) {
  if (first == nullptr) return;
  first->hit = true;
  first->normal = glm::dot(sp.ng, sp.wo) >= 0.0f ? sp.ng : -sp.ng;
  first->albedo = sp.bsdf().albedo();
  first->depth = t;
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
                              glm::vec2 u, TraceCounters& counters) {
  ShadowQuery q;
  if (!prepare_direct_light(ctx, sp, leaving_origin(sp), strategy, u, q)) return glm::vec3(0.0f);
  ++counters.shadow_rays;
  return ctx.backend->occluded(q.ray, counters.query_stats()) ? glm::vec3(0.0f) : q.contribution;
}

glm::vec3 escaped_radiance(const SceneContext& ctx, const glm::vec3& dir, SamplingStrategy strategy,
                           bool prev_delta, float prev_bsdf_pdf) {
  if (ctx.environment == nullptr) return glm::vec3(0.0f);
  const glm::vec3 le = ctx.environment->eval(dir);
  if (prev_delta || ctx.lights == nullptr) return le;
  return le * emission_weight(strategy, prev_delta, prev_bsdf_pdf, ctx.lights->pdf_environment(dir));
}

glm::vec3 weighted_surface_emission(const SceneContext& ctx, const SurfacePoint& sp, const Hit& hit,
                                    SamplingStrategy strategy, bool prev_delta, float prev_bsdf_pdf,
                                    const glm::vec3& prev_p, float connection_factor) {
  const glm::vec3 le = sp.geom->emission;
  if (prev_delta || ctx.lights == nullptr) return le;
  // The hit came from Backend::intersect_ids, whose ng is unspecified: pdf_surface reads a sphere's normal,
  // so it gets the surface point's.
  Hit at = hit;
  at.ng = sp.ng;
  const float light_pdf = ctx.lights->pdf_surface(prev_p, at, sp.p);
  if (connection_factor > 0.0f && strategy == SamplingStrategy::Mis) {
    const float c = connection_factor * ctx.lights->emission_pdf_area(at);
    return le * power_heuristic3(prev_bsdf_pdf, light_pdf, c);
  }
  return le * emission_weight(strategy, prev_delta, prev_bsdf_pdf, light_pdf);
}

}  // namespace twinray
