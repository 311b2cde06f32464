#pragma once
// Unidirectional path tracing with next-event estimation.
//
// At every non-delta vertex one light sample (shadow ray) and one BSDF sample (the continuation) are
// taken; emission reached by the continuation is weighted against the light sample by the power heuristic
// (SamplingStrategy::Mis). Delta vertices (mirror, glass) take no light sample, and emission seen after
// them counts fully. Paths end at max_depth segments, when the BSDF absorbs, or by Russian roulette from
// rr_depth segments on (core/render/russian_roulette.h). With light_traced_caustics, emission reached right
// after a delta vertex by a path whose first vertex is non-delta is left to the light tracer
// (core/render/light_tracer.h), which counts those caustic paths instead. With splits > 1 a path continues
// `splits` times from its first non-delta vertex, each continuation with 1/splits of the throughput, its own
// Sampler::split and a roulette on the unsplit throughput (docs/rendering.md#path-splitting). With
// light_connections > 0 each camera sample also traces light subpaths of one segment and joins its non-delta
// vertices up to kLightConnectionMaxDepth segments deep to their hits: a third strategy for the paths whose
// last two vertices are a diffuse bounce and the light (core/render/light_connection.h).
//
// Wavefront: the paths of a batch (one sample of each pixel of a tile) advance together, one segment at a
// time: all their rays are traced, then every path is shaded (emission, light sample, BSDF sample,
// roulette), then all their shadow rays are traced. Why: shading one path is a chain of dependent
// divisions, square roots and loads, each waiting for the last; with one path at a time the core waits on
// that chain, and then on the traversal that depends on it. Shading many independent paths back to back
// lets the out-of-order core overlap their chains (measured: 10-15% less CPU time per sample on the Cornell
// box, one thread). The rays are traced one call per ray: the backends' batch calls sort rays along a
// Morton curve into a fresh vector, which costs more than it saves on these small scenes. Every
// path still draws its random numbers in the same order and adds its contributions in the same order as
// when traced alone, so the radiance of each sample is bit for bit what radiance(ray, ...) returns.

#include "core/render/integrator.h"

namespace twinray {

class PathIntegrator final : public Integrator {
 public:
  // Light connections are kept only where they apply (IntegratorSettings::light_connections), at most
  // kMaxLightConnections.
  PathIntegrator(const SceneContext& ctx, const IntegratorSettings& settings);
  IntegratorKind kind() const override { return IntegratorKind::Path; }
  glm::vec3 radiance(const Ray& camera_ray, Sampler& sampler, TraceCounters& counters, FirstHitInfo* first) const override;
  void radiance(std::span<CameraSample> samples, std::span<glm::vec3> out, std::span<FirstHitInfo> first,
                TraceCounters& counters) const override;

  // Paths advanced together at most; larger batches are traced in chunks of this size. 256 (a 16 x 16
  // tile) keeps a chunk's state, rays and hits (~70 KiB, one reused set per thread) within the L2 cache.
  static constexpr std::size_t kMaxBatch = 256;

 private:
  // At most kCapacity samples; the capacity sizes the chunk's working arrays (1 for radiance(ray, ...), so
  // a lone path does not walk arrays sized for 256).
  template <std::size_t kCapacity>
  void trace_chunk(std::span<CameraSample> samples, std::span<glm::vec3> out, std::span<FirstHitInfo> first,
                   TraceCounters& counters) const;

  const SceneContext& ctx_;
  IntegratorSettings settings_;
};

}  // namespace twinray
