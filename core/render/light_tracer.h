#pragma once
// Light tracing for caustics seen directly: particles leave the area lights, and every diffuse vertex
// they reach after a specular chain is connected to the pinhole camera (the t = 1 strategy of
// bidirectional path tracing). It takes over, as a partition of path space, the paths the path tracer can
// find only by a BSDF sample that happens to pass through the specular chain onto the light:
//
//   E x1 ... x_k S+ L  with x1 non-delta and every vertex between the last non-delta one and the light
//   delta (at least one): light paths L S+ D ... connected to the camera at each non-delta vertex.
//
// The path tracer drops exactly these paths (IntegratorSettings::light_traced_caustics; the emission its
// BSDF samples reach after a delta vertex when its first vertex is non-delta), so each path of the image
// is counted by one strategy and the sum stays unbiased without MIS weights. Every path the light tracer
// makes has a non-delta x1 (it connects to the camera there) and a delta vertex next to the light (a light
// path whose first hit is not specular is dropped: the path tracer's light sampling covers those), and
// every such path is made by exactly one light path prefix, at its unique number of segments.
//
// Per light path: a surface light chosen as the light sampler chooses (power), a point uniform on it and a
// cosine-weighted direction on its emitting side (LightSampler::sample_emission); delta bounces are
// followed; once in caustic state, each non-delta vertex y is connected to the camera (shadow ray, raster
// position, importance PinholeCamera::project, BSDF toward the camera with the BSDFs' one-sided rules)
// and the path goes on by BSDF sampling. Depth: a connection from the vertex reached by segment k makes a
// path of k + 1 segments, counted only when k + 1 <= max_depth, the path tracer's convention. Russian
// roulette: the path tracer's rule (russian_roulette.h) on the product of BSDF weights (not on the light's
// power, which has units), without the eta^2 term, since importance transport carries no 1/eta^2.
// Refraction: the BSDFs return radiance weights (1/eta^2 per refraction); flux crossing an interface is not
// compressed, so light paths multiply the weight back by eta^2 (pbrt's TransportMode::Importance).
//
// Determinism: light path i draws every random number from Sampler(kind, seed ^ kLightSeedSalt, i mod P,
// i div P), P the pixel count: a function of the global light-path index only. Its splats go to the
// chunk's list, and the renderer adds the lists to the film in chunk order, so the image does not depend
// on threads, scheduling, or --spp versus --time. One light path per camera sample.

#include "core/camera/pinhole_camera.h"
#include "core/render/integrator.h"

#include <cstdint>
#include <span>
#include <vector>

namespace twinray {

// One contribution of a light path to a pixel: (its part of) the pixel's sum over light paths, which the
// film divides by the samples per pixel.
struct Splat {
  std::uint32_t pixel = 0;
  glm::vec3 value{0.0f};
};

// Which light paths connect to the camera.
//   Caustics   the renderer's: only after a specular first hit (the partition above);
//   AllDiffuse every non-delta vertex, first hit included: light tracing then counts every path with a
//              non-delta x1, which the path tracer counts too. Not a rendering mode: tests check the light
//              tracer's normalisation with it against the path tracer's direct lighting (max_depth 2).
enum class LightPathSet { Caustics, AllDiffuse };

class LightTracer {
 public:
  // Salt mixed into the render seed for light paths, so that light path i and camera sample i (same pixel
  // and sample index) draw unrelated values.
  static constexpr std::uint64_t kLightSeedSalt = 0x6c696768742d7472ull;  // "light-tr"

  // `ctx.lights` must have surface lights; ctx and camera must outlive the tracer.
  LightTracer(const SceneContext& ctx, const IntegratorSettings& settings, const PinholeCamera& camera,
              SamplerKind sampler, std::uint64_t seed, LightPathSet paths = LightPathSet::Caustics);

  // Traces light paths [begin, end) (global indices), appending their splats to `out` in path order.
  // Non-finite contributions are dropped and counted in `nonfinite`.
  void trace(std::uint64_t begin, std::uint64_t end, std::vector<Splat>& out, TraceCounters& counters,
             std::uint64_t& nonfinite) const;

 private:
  void trace_path(std::uint64_t index, std::vector<Splat>& out, TraceCounters& counters,
                  std::uint64_t& nonfinite) const;

  const SceneContext& ctx_;
  IntegratorSettings settings_;
  const PinholeCamera& camera_;
  SamplerKind sampler_;
  std::uint64_t seed_;
  std::uint64_t pixel_count_;
  LightPathSet paths_;
};

}  // namespace twinray
