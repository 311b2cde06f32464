#include "core/render/path_integrator.h"

#include "core/render/light_transport.h"
#include "core/render/russian_roulette.h"

#include <glm/geometric.hpp>

#include <algorithm>

namespace twinray {

glm::vec3 PathIntegrator::radiance(const Ray& camera_ray, Sampler& sampler, TraceCounters& counters,
                                   FirstHitInfo* first) const {
  const SamplingStrategy strategy = settings_.strategy;
  glm::vec3 result(0.0f);
  glm::vec3 throughput(1.0f);
  float eta_scale = 1.0f;
  bool prev_delta = true;  // the camera ray is a "delta" start: emission seen directly counts fully
  float prev_bsdf_pdf = 0.0f;
  glm::vec3 prev_p(0.0f);
  Ray ray = camera_ray;

  for (int depth = 1;; ++depth) {
    Hit hit;
    ++counters.closest_hit_rays;
    if (!ctx_.backend->intersect(ray, hit, counters.query_stats())) {
      result += throughput * escaped_radiance(ctx_, ray.dir, strategy, prev_delta, prev_bsdf_pdf);
      break;
    }
    const SurfacePoint sp = make_surface_point(ctx_, ray, hit);
    if (depth == 1) record_first_hit(first, sp, hit.t);
    result += throughput * surface_emission(ctx_, sp, hit, strategy, prev_delta, prev_bsdf_pdf, prev_p);

    if (settings_.max_depth >= 0 && depth >= settings_.max_depth) break;
    if (sp.bsdf->is_black()) break;

    if (!sp.bsdf->is_delta())
      result += throughput * sample_direct_light(ctx_, sp, strategy, sampler, counters);

    const float u_lobe = sampler.next_1d();
    const glm::vec2 u = sampler.next_2d();
    const std::optional<BsdfSample> bs = sp.bsdf->sample(sp.wo, sp.ng, u_lobe, u);
    if (!bs || max_component(bs->weight) <= 0.0f) break;
    throughput *= bs->weight;
    eta_scale *= bs->eta_ti * bs->eta_ti;
    prev_delta = bs->delta;
    prev_bsdf_pdf = bs->pdf;
    prev_p = sp.p;
    ray = spawn_ray(sp, bs->wi);

    if (!survive_roulette(depth, settings_.rr_depth, eta_scale, throughput, sampler)) break;
  }
  return result;
}

}  // namespace twinray
