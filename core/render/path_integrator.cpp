#include "core/render/path_integrator.h"

#include "core/render/light_transport.h"
#include "core/render/russian_roulette.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cstdint>

namespace twinray {
namespace {

// What a path carries from one segment to the next (besides its ray and its sampler).
struct PathState {
  glm::vec3 throughput{1.0f};
  float eta_scale = 1.0f;      // product of eta^2 over refractions, undone by the roulette
  glm::vec3 prev_p{0.0f};      // the vertex the current ray left
  float prev_bsdf_pdf = 0.0f;  // the density the current ray's direction was sampled with
  bool prev_delta = true;      // the camera ray is a "delta" start: emission seen directly counts fully
  // The light tracer counts this path's emission when the last vertex was delta (light_tracer.h): set at a
  // non-delta first vertex when light_traced_caustics is on.
  bool caustic_by_light_tracer = false;
};

// Paths still going, compacted after every segment: rays[a] and hits[a] belong to path active[a]. Vertices
// that scatter (the path goes on or takes a light sample): the point, its path, its two 2D sampler values.
// Shadow rays of the current segment and what each adds to its path when unoccluded.
template <std::size_t kCapacity>
struct ChunkScratch {
  std::array<PathState, kCapacity> state;
  std::array<std::uint16_t, kCapacity> active;
  std::array<Ray, kCapacity> rays;
  std::array<Hit, kCapacity> hits;
  std::array<SurfacePoint, kCapacity> vertex;
  std::array<std::uint16_t, kCapacity> vertex_path;
  std::array<glm::vec2, kCapacity> u_light, u_bsdf;
  std::array<Ray, kCapacity> shadow_rays;
  std::array<glm::vec3, kCapacity> shadow_contribution;
  std::array<std::uint16_t, kCapacity> shadow_owner;
};

}  // namespace

glm::vec3 PathIntegrator::radiance(const Ray& camera_ray, Sampler& sampler, TraceCounters& counters,
                                   FirstHitInfo* first) const {
  CameraSample sample{camera_ray, sampler};
  glm::vec3 result(0.0f);
  trace_chunk<1>(std::span(&sample, 1), std::span(&result, 1),
              first != nullptr ? std::span(first, 1) : std::span<FirstHitInfo>(), counters);
  sampler = sample.sampler;
  return result;
}

void PathIntegrator::radiance(std::span<CameraSample> samples, std::span<glm::vec3> out, std::span<FirstHitInfo> first,
                              TraceCounters& counters) const {
  for (std::size_t begin = 0; begin < samples.size(); begin += kMaxBatch) {
    const std::size_t n = std::min(kMaxBatch, samples.size() - begin);
    trace_chunk<kMaxBatch>(samples.subspan(begin, n), out.subspan(begin, n), first.empty() ? first : first.subspan(begin, n),
                counters);
  }
}

template <std::size_t kCapacity>
void PathIntegrator::trace_chunk(std::span<CameraSample> samples, std::span<glm::vec3> out,
                                 std::span<FirstHitInfo> first, TraceCounters& counters) const {
  const SamplingStrategy strategy = settings_.strategy;
  const std::size_t n = samples.size();
  // The chunk's working arrays: per thread and reused, because constructing them (their members have
  // default initialisers) cost about 2% of the render per chunk of 256 samples. Every entry is written
  // before it is read.
  static thread_local ChunkScratch<kCapacity> scratch;
  auto& [state, active, rays, hits, vertex, vertex_path, u_light, u_bsdf, shadow_rays, shadow_contribution,
         shadow_owner] = scratch;

  for (std::size_t i = 0; i < n; ++i) {
    out[i] = glm::vec3(0.0f);
    state[i] = PathState{};
    active[i] = static_cast<std::uint16_t>(i);
    rays[i] = samples[i].ray;
  }
  // Each segment in stages, each stage a loop over the paths: short loop bodies whose iterations are
  // independent, so the core overlaps them.
  std::size_t n_active = n;
  for (int depth = 1; n_active > 0; ++depth) {
    counters.closest_hit_rays += n_active;
    for (std::size_t a = 0; a < n_active; ++a) ctx_.backend->intersect(rays[a], hits[a], counters.query_stats());

    // Hits: escaped radiance, emission, and the vertices that scatter.
    const bool last_segment = settings_.max_depth >= 0 && depth >= settings_.max_depth;
    std::size_t n_vertices = 0;
    for (std::size_t a = 0; a < n_active; ++a) {
      const std::uint16_t i = active[a];
      const PathState& st = state[i];
      const Hit& hit = hits[a];
      if (!hit.found()) {
        out[i] += st.throughput * escaped_radiance(ctx_, rays[a].dir, strategy, st.prev_delta, st.prev_bsdf_pdf);
        continue;
      }
      const SurfacePoint sp = make_surface_point(ctx_, rays[a], hit);
      if (depth == 1 && !first.empty()) record_first_hit(&first[i], sp, hit.t);
      // Emission after a delta vertex behind a non-delta first vertex belongs to the light tracer.
      if (sp.geom->emissive && !(st.caustic_by_light_tracer && st.prev_delta))
        out[i] += st.throughput * surface_emission(ctx_, sp, hit, strategy, st.prev_delta, st.prev_bsdf_pdf, st.prev_p);
      if (last_segment || sp.bsdf().is_black()) continue;
      vertex[n_vertices] = sp;
      vertex_path[n_vertices] = i;
      ++n_vertices;
    }

    // Sampler dimensions of a vertex: the light sample (2D; drawn at delta vertices too, unused there, so
    // that every vertex takes the same dimensions), the BSDF sample (2D), the roulette (1D, only once it
    // plays).
    for (std::size_t v = 0; v < n_vertices; ++v) {
      Sampler& sampler = samples[vertex_path[v]].sampler;
      u_light[v] = sampler.next_2d();
      u_bsdf[v] = sampler.next_2d();
    }

    // Light samples at the non-delta vertices.
    std::size_t n_shadow = 0;
    for (std::size_t v = 0; v < n_vertices; ++v) {
      if (vertex[v].bsdf().is_delta()) continue;
      ShadowQuery q;
      if (!prepare_direct_light(ctx_, vertex[v], strategy, u_light[v], q)) continue;
      const std::uint16_t i = vertex_path[v];
      shadow_rays[n_shadow] = q.ray;
      shadow_contribution[n_shadow] = state[i].throughput * q.contribution;
      shadow_owner[n_shadow] = i;
      ++n_shadow;
    }

    // BSDF samples, roulette, the next segment's rays.
    std::size_t n_next = 0;
    for (std::size_t v = 0; v < n_vertices; ++v) {
      const SurfacePoint& sp = vertex[v];
      const std::uint16_t i = vertex_path[v];
      PathState& st = state[i];
      if (depth == 1) st.caustic_by_light_tracer = settings_.light_traced_caustics && !sp.bsdf().is_delta();
      BsdfSample bs;
      if (!sp.bsdf().sample(sp.wo, sp.ng, u_bsdf[v], bs) || max_component(bs.weight) <= 0.0f) continue;
      st.throughput *= bs.weight;
      st.eta_scale *= bs.eta_ti * bs.eta_ti;
      st.prev_delta = bs.delta;
      st.prev_bsdf_pdf = bs.pdf;
      st.prev_p = sp.p;
      if (!survive_roulette(depth, settings_.rr_depth, st.eta_scale, st.throughput, samples[i].sampler)) continue;
      rays[n_next] = spawn_ray(sp, bs.wi);
      active[n_next] = i;
      ++n_next;
    }

    // The light samples of this segment, added before the next segment's emission as a lone path would.
    counters.shadow_rays += n_shadow;
    for (std::size_t k = 0; k < n_shadow; ++k)
      if (!ctx_.backend->occluded(shadow_rays[k], counters.query_stats())) out[shadow_owner[k]] += shadow_contribution[k];
    n_active = n_next;
  }
}

}  // namespace twinray
