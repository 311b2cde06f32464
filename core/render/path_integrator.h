#pragma once
// Unidirectional path tracing with next-event estimation.
//
// At every non-delta vertex one light sample (shadow ray) and one BSDF sample (the continuation) are
// taken; emission reached by the continuation is weighted against the light sample by the power heuristic
// (SamplingStrategy::Mis). Delta vertices (mirror, glass) take no light sample, and emission seen after
// them counts fully. Paths end at max_depth segments, when the BSDF absorbs, or by Russian roulette from
// rr_depth segments on (core/render/russian_roulette.h).

#include "core/render/integrator.h"

namespace twinray {

class PathIntegrator final : public Integrator {
 public:
  PathIntegrator(const SceneContext& ctx, const IntegratorSettings& settings) : ctx_(ctx), settings_(settings) {}
  IntegratorKind kind() const override { return IntegratorKind::Path; }
  glm::vec3 radiance(const Ray& camera_ray, Sampler& sampler, TraceCounters& counters, FirstHitInfo* first) const override;

 private:
  const SceneContext& ctx_;
  IntegratorSettings settings_;
};

}  // namespace twinray
