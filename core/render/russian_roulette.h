#pragma once
// Russian roulette, shared by both integrators.
//
// From rr_depth segments on, a path survives with probability q = min(1, kSurvivalScale * max(throughput) *
// eta^2) and is divided by q. The eta^2 undoes the 1/eta^2 radiance scaling of refraction, so a path is not
// killed for being inside glass. Any q in (0, 1] keeps the estimator unbiased; q only trades time against noise.
//
// Why kSurvivalScale = 3 rather than pbrt-v4's 1 (q = max(throughput), which lifts every survivor back to a
// throughput of 1): a rouletted path adds variance of about throughput^2 E[L^2] (1/q - 1), so with q equal to
// the throughput the moderately attenuated paths (throughput 0.3 to 0.9, the bulk of the light in a white box)
// pay most of it, for little saved time: each of them would have gone on for only a few segments. With a scale
// of 3 only paths whose throughput has dropped below 1/3 are rouletted, and those with probability 3 times
// their throughput. Measured (docs/rendering.md#russian-roulette, 256x256, 32 spp, seed pairs, relMSE from
// the pairs' differences): on the Cornell box 9.0% more rays and 20% less noise than the scale 1 (efficiency
// +12.5%); on the mirror-and-glass box 10% more rays and 27% less noise; no roulette at all (rr_depth 1000)
// removes 23% of the noise for 87% more rays.
//
// Why a path with throughput >= 1 is never rouletted (the earlier rule capped q at 0.95 for every path, as
// Mitsuba 3 does): a specular glass chain keeps throughput exactly 1, and with q = 0.95 a chain of k roulette
// steps weighs 0.95^-k. Inside a faceted ior-4 sphere a chain escapes with probability p per bounce, and the
// estimator's second moment, sum ((1 - p) / 0.95)^k, diverges when p < 5%: the mean is right but sample means
// sit low, because the heavy tail is rarely drawn. Measured (64x64, 256 spp, icosphere of 1280 triangles,
// ior 4, white sky, exact answer 1): 0.9838 with the 0.95 cap, 1.0000 without roulette.
//
// Termination: a path whose throughput never drops below 1/3 (an albedo-1 closed enclosure) would run forever
// with unlimited depth, so from kForcedRouletteDepth segments on q is capped at kMaxSurvival, which ends every
// path with probability 1 and stays unbiased. Both constants are about that tail: in the icosphere above,
// 0.17% of the energy arrives by paths longer than 1000 segments (1.5% beyond 256). With a 0.95 cap from
// segment 1024 on, the tail's heavy weights again showed (0.9987, 4 standard errors 0.0011); with 0.999 the
// second moment stays finite unless a chain escapes with less than 0.1% probability per bounce, and the
// image reads 0.99998. The price is paid only by paths that never lose energy: in an albedo-1 closed box a
// path runs about 1024 + 1000 segments.

#include "core/sampling/rng.h"

#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include <algorithm>

namespace twinray {

inline constexpr int kForcedRouletteDepth = 1024;
inline constexpr float kMaxSurvival = 0.999f;
// Survival probability per unit of throughput (see above): paths with max(throughput) * eta^2 >= 1/3 are
// never rouletted before kForcedRouletteDepth.
inline constexpr float kSurvivalScale = 3.0f;

// Survival probability of a path after `depth` segments; 1 means no roulette.
inline float roulette_survival(int depth, int rr_depth, const glm::vec3& throughput, float eta_scale) {
  if (depth < rr_depth) return 1.0f;
  const float q = kSurvivalScale * std::max({throughput.x, throughput.y, throughput.z}) * eta_scale;
  return std::min(q, depth < kForcedRouletteDepth ? 1.0f : kMaxSurvival);
}

// Plays the roulette: false when the path ends; otherwise the throughput is reweighted by 1/q.
// Draws a random number only when q < 1. `Generator` is a Sampler or an Rng (anything with next_float()).
template <class Generator>
inline bool survive_roulette(int depth, int rr_depth, float eta_scale, glm::vec3& throughput, Generator& rng) {
  const float q = roulette_survival(depth, rr_depth, throughput, eta_scale);
  if (q >= 1.0f) return true;
  if (!(rng.next_float() < q)) return false;  // also ends a path with q NaN or 0
  throughput /= q;
  return true;
}

}  // namespace twinray
