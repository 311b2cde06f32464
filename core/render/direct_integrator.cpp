#include "core/render/direct_integrator.h"

#include "core/render/light_transport.h"
#include "core/render/russian_roulette.h"

#include <glm/geometric.hpp>

#include <algorithm>

namespace twinray {

glm::vec3 DirectIntegrator::radiance(const Ray& camera_ray, Sampler& sampler, TraceCounters& counters,
                                     FirstHitInfo* first) const {
  const SamplingStrategy strategy = settings_.strategy;
  glm::vec3 result(0.0f);
  glm::vec3 throughput(1.0f);
  float eta_scale = 1.0f;
  bool prev_delta = true;
  bool lit_vertex_done = false;  // true once the non-delta vertex has been shaded
  float prev_bsdf_pdf = 0.0f;
  glm::vec3 prev_p(0.0f);
  Ray ray = camera_ray;

  for (int depth = 1;; ++depth) {
    Hit hit;
    ++counters.closest_hit_rays;
    if (!ctx_.backend->intersect_ids(ray, hit, counters.query_stats())) {
      result += throughput * escaped_radiance(ctx_, ray.dir, strategy, prev_delta, prev_bsdf_pdf);
      break;
    }
    const SurfacePoint sp = make_surface_point(ctx_, ray, hit);
    if (depth == 1) record_first_hit(first, sp, hit.t);
    result += throughput * surface_emission(ctx_, sp, hit, strategy, prev_delta, prev_bsdf_pdf, prev_p);
    // The BSDF-sampled segment from the lit vertex exists only to find emission.
    if (lit_vertex_done) break;
    if (settings_.max_depth >= 0 && depth >= settings_.max_depth) break;
    const Bsdf& bsdf = sp.bsdf();
    if (bsdf.is_black()) break;

    if (!bsdf.is_delta()) {
      result += throughput * sample_direct_light(ctx_, sp, strategy, sampler.next_2d(), counters);
      lit_vertex_done = true;
      // With light sampling only, the BSDF continuation could only find emission that light sampling
      // cannot produce, and every emitter here can be sampled: skip it.
      if (strategy == SamplingStrategy::Light && ctx_.lights != nullptr) break;
    }
    const std::optional<BsdfSample> bs = bsdf.sample(sp.wo, sp.ng, sampler.next_2d());
    if (!bs || max_component(bs->weight) <= 0.0f) break;
    throughput *= bs->weight;
    prev_delta = bs->delta;
    prev_bsdf_pdf = bs->pdf;
    prev_p = sp.p;
    ray = spawn_ray(sp, bs->wi);
    eta_scale *= bs->eta_ti * bs->eta_ti;

    // Delta chains can be endless (total internal reflection inside a glass box): the same Russian
    // roulette as the path integrator ends them without bias.
    if (!survive_roulette(depth, settings_.rr_depth, eta_scale, throughput, sampler)) break;
  }
  return result;
}

}  // namespace twinray
