#pragma once
// Direct lighting: emission plus one bounce of light at the first non-delta surface.
//
// The camera path follows mirror and glass chains (delta bounces, up to max_depth segments); at the first
// non-delta vertex it takes one light sample and one BSDF sample, MIS weighted exactly like the path
// integrator, and stops. Equal to the path integrator with max_depth 2 on scenes without delta materials.

#include "core/render/integrator.h"

namespace twinray {

class DirectIntegrator final : public Integrator {
 public:
  DirectIntegrator(const SceneContext& ctx, const IntegratorSettings& settings) : ctx_(ctx), settings_(settings) {}
  IntegratorKind kind() const override { return IntegratorKind::Direct; }
  glm::vec3 radiance(const Ray& camera_ray, Sampler& sampler, TraceCounters& counters, FirstHitInfo* first) const override;

 private:
  const SceneContext& ctx_;
  IntegratorSettings settings_;
};

}  // namespace twinray
