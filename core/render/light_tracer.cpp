#include "core/render/light_tracer.h"

#include "core/render/light_transport.h"
#include "core/render/russian_roulette.h"

#include <glm/geometric.hpp>

#include <cmath>

namespace twinray {
namespace {

bool finite3(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

LightTracer::LightTracer(const SceneContext& ctx, const IntegratorSettings& settings, const PinholeCamera& camera,
                         SamplerKind sampler, std::uint64_t seed, LightPathSet paths)
    : ctx_(ctx),
      settings_(settings),
      camera_(camera),
      sampler_(sampler),
      seed_(seed),
      pixel_count_(static_cast<std::uint64_t>(camera.width()) * static_cast<std::uint64_t>(camera.height())),
      paths_(paths) {}

void LightTracer::trace(std::uint64_t begin, std::uint64_t end, std::vector<Splat>& out, TraceCounters& counters,
                        std::uint64_t& nonfinite) const {
  for (std::uint64_t i = begin; i < end; ++i) trace_path(i, out, counters, nonfinite);
}

void LightTracer::trace_path(std::uint64_t index, std::vector<Splat>& out, TraceCounters& counters,
                             std::uint64_t& nonfinite) const {
  if (ctx_.lights == nullptr) return;
  Sampler sampler(sampler_, seed_ ^ kLightSeedSalt, index % pixel_count_, static_cast<std::uint32_t>(index / pixel_count_));
  const glm::vec2 u_point = sampler.next_2d();
  const glm::vec2 u_dir = sampler.next_2d();
  EmissionSample es;
  if (!ctx_.lights->sample_emission(u_point, u_dir, es)) return;

  glm::vec3 beta = es.weight;   // flux carried, in the units the splats need
  glm::vec3 scale(1.0f);        // product of the BSDF weights alone: what the roulette looks at
  Ray ray;
  ray.org = offset_ray_origin(es.point, es.normal, es.error_scale);
  ray.dir = es.dir;
  ray.tmin = 0.0f;
  ray.tmax = std::numeric_limits<float>::infinity();

  const int max_depth = settings_.max_depth;
  // depth: segments of the light path up to the vertex being shaded; its connection makes depth + 1.
  for (int depth = 1; max_depth < 0 || depth + 1 <= max_depth; ++depth) {
    ++counters.closest_hit_rays;
    Hit hit;
    ctx_.backend->intersect_ids(ray, hit, counters.query_stats());
    if (!hit.found()) return;
    // Decided from the material before the surface point is computed: most light paths end here.
    const Bsdf& bsdf = ctx_.geoms[hit.geom_id].bsdf;
    if (bsdf.is_black()) return;
    // The first hit must be specular: L D ... paths belong to the path tracer's light sampling.
    if (depth == 1 && !bsdf.is_delta() && paths_ == LightPathSet::Caustics) return;
    const SurfacePoint sp = make_surface_point(ctx_, ray, hit);
    if (!bsdf.is_delta()) {
      PinholeCamera::Projection pr;
      if (camera_.project(sp.p, pr)) {
        // eval(wo, wi) is f |cos(ng, wi)|: with wi toward the camera it is the cosine of the connection.
        // Only non-delta (Lambertian) BSDFs get here, and theirs is symmetric in wo and wi, one-sided rule
        // included (both directions must be on the front), so swapping the roles is exact.
        const glm::vec3 f = bsdf.eval(sp.wo, pr.to_camera, sp.ng);
        if (max_component(f) > 0.0f) {
          Ray shadow;
          shadow.org = offset_ray_origin(sp.p, glm::dot(pr.to_camera, sp.ng) > 0.0f ? sp.ng : -sp.ng, sp.error_scale);
          const glm::vec3 d = camera_.position() - shadow.org;
          const float dist2 = glm::dot(d, d);
          if (dist2 > 0.0f) {
            const float inv_dist = 1.0f / std::sqrt(dist2);
            shadow.dir = d * inv_dist;
            shadow.tmin = 0.0f;
            // The camera is a point in free space, not on a surface: the shortening (light_transport.h) only
            // keeps a surface through the camera position itself from occluding.
            shadow.tmax = dist2 * inv_dist * (1.0f - kShadowRayShortening);
            ++counters.shadow_rays;
            if (!ctx_.backend->occluded(shadow, counters.query_stats())) {
              const glm::vec3 value = beta * f * pr.importance;
              if (finite3(value)) {
                out.push_back(Splat{static_cast<std::uint32_t>(pr.y) * static_cast<std::uint32_t>(camera_.width()) + pr.x,
                                    value});
              } else {
                ++nonfinite;
              }
            }
          }
        }
      }
      // The vertex reached next needs depth + 2 segments to connect.
      if (max_depth >= 0 && depth + 2 > max_depth) return;
    }

    BsdfSample bs;
    if (!bsdf.sample(sp.wo, sp.ng, sampler.next_2d(), bs)) return;
    // Importance transport: undo the BSDF's 1/eta^2 radiance compression of a refraction.
    const glm::vec3 weight = bs.weight * (bs.eta_ti * bs.eta_ti);
    if (!(max_component(weight) > 0.0f)) return;
    beta *= weight;
    scale *= weight;
    const float q = roulette_survival(depth, settings_.rr_depth, scale, 1.0f);
    if (q < 1.0f) {
      if (!(sampler.next_float() < q)) return;
      beta /= q;
      scale /= q;
    }
    ray = spawn_ray(sp, bs.wi);
  }
}

}  // namespace twinray
