#pragma once
// Monte Carlo irradiance with an environment light's own importance sampler: the independent check of
// sample() and pdf() against the quadrature of environment_irradiance().

#include "core/lights/environment_light.h"
#include "core/sampling/rng.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace twinray::testing {

struct SampledEstimate {
  double mean = 0.0;
  double std_error = 0.0;
};

// Mean and standard error of L_red(w) max(0, n.w) / pdf(w) over `count` samples of the light (samples
// with pdf 0 count as 0, as a renderer skips them).
inline SampledEstimate sampled_red_irradiance(const EnvironmentLight& light, glm::vec3 n, int count, Rng rng) {
  double sum = 0.0, sum2 = 0.0;
  for (int i = 0; i < count; ++i) {
    const EnvironmentLight::Sample s = light.sample(glm::vec2(rng.next_float(), rng.next_float()));
    const double v = s.pdf > 0.0f ? s.radiance.x * std::max(0.0f, glm::dot(n, s.dir)) / s.pdf : 0.0;
    sum += v;
    sum2 += v * v;
  }
  const double mean = sum / count;
  return {mean, std::sqrt(std::max(0.0, sum2 / count - mean * mean) / count)};
}

}  // namespace twinray::testing
