#include "core/render/path_integrator.h"

#include "core/render/light_connection.h"
#include "core/render/light_transport.h"
#include "core/render/russian_roulette.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

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
  bool split = false;  // splitting: the path's continuations have been split off (only once per path)
  // Light connections: at a non-delta vertex behind a non-delta one, connection_factor(...); after its BSDF
  // sample that times |cos(n, wi)|; 0 elsewhere and without connections (light_connection.h).
  float connection_factor = 0.0f;
  bool from_split = false;  // the current ray is one of `splits` continuations of its previous vertex
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
  std::array<glm::vec3, kCapacity> vertex_origin;  // leaving_origin of the non-delta vertices
  std::array<std::uint16_t, kCapacity> vertex_path;
  std::array<glm::vec2, kCapacity> u_light, u_bsdf;
  // Light connections: each path's light subpaths, traced at its first vertex (their two 2D sampler values,
  // the ray to the first hit and that hit, in trace order with their path), and per path the emission sample
  // and the first hit as a LightVertex (`light_vertex_valid`: non-delta, so connections can be made to it).
  static constexpr std::size_t kLightCapacity = kCapacity * kMaxLightConnections;
  std::array<glm::vec2, kLightCapacity> u_emit_point, u_emit_dir;
  std::array<Ray, kLightCapacity> light_rays;
  std::array<Hit, kLightCapacity> light_hits;
  std::array<std::uint32_t, kLightCapacity> light_slot;
  std::array<EmissionSample, kLightCapacity> emission;
  std::array<LightVertex, kLightCapacity> light_vertex;
  std::array<bool, kLightCapacity> light_vertex_valid;
  // A segment's shadow rays: a light sample per vertex, and the light connections of the first vertices.
  std::array<Ray, kCapacity + kLightCapacity> shadow_rays;
  std::array<glm::vec3, kCapacity + kLightCapacity> shadow_contribution;
  std::array<std::uint16_t, kCapacity + kLightCapacity> shadow_owner;
  // Splitting: the first non-delta vertices waiting for their continuations, each with its path, the
  // segments that reached it, the path's state and its sampler as they were before its BSDF sample.
  std::array<SurfacePoint, kCapacity> split_vertex;
  std::array<glm::vec3, kCapacity> split_origin;
  std::array<std::uint16_t, kCapacity> split_path;
  std::array<int, kCapacity> split_depth;
  std::array<PathState, kCapacity> split_state;
  std::array<std::optional<Sampler>, kCapacity> split_sampler;  // Sampler has no default state
};

}  // namespace

PathIntegrator::PathIntegrator(const SceneContext& ctx, const IntegratorSettings& settings)
    : ctx_(ctx), settings_(settings) {
  // The connections' weights assume the path tracer's light samples and paths of three segments.
  const bool applies = settings.strategy == SamplingStrategy::Mis && (settings.max_depth < 0 || settings.max_depth >= 3) &&
                       ctx.lights != nullptr && ctx.lights->has_surface_lights();
  settings_.light_connections = applies ? std::min(settings.light_connections, kMaxLightConnections) : 0;
}

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
  const std::uint32_t splits = std::max(settings_.splits, 1u);
  // The chunk's working arrays: per thread and reused, because constructing them (their members have
  // default initialisers) cost about 2% of the render per chunk of 256 samples. Every entry is written
  // before it is read.
  static thread_local ChunkScratch<kCapacity> scratch;
  // Named references, not a structured binding: the lambdas below capture them, which clang before 16
  // (the sanitizer build) does not allow for structured bindings.
  auto& state = scratch.state;
  auto& active = scratch.active;
  auto& rays = scratch.rays;
  auto& hits = scratch.hits;
  auto& vertex = scratch.vertex;
  auto& vertex_origin = scratch.vertex_origin;
  auto& vertex_path = scratch.vertex_path;
  auto& u_light = scratch.u_light;
  auto& u_bsdf = scratch.u_bsdf;
  auto& shadow_rays = scratch.shadow_rays;
  auto& shadow_contribution = scratch.shadow_contribution;
  auto& shadow_owner = scratch.shadow_owner;
  auto& split_vertex = scratch.split_vertex;
  auto& split_origin = scratch.split_origin;
  auto& split_path = scratch.split_path;
  auto& split_depth = scratch.split_depth;
  auto& split_state = scratch.split_state;
  auto& split_sampler = scratch.split_sampler;
  auto& u_emit_point = scratch.u_emit_point;
  auto& u_emit_dir = scratch.u_emit_dir;
  auto& light_rays = scratch.light_rays;
  auto& light_hits = scratch.light_hits;
  auto& light_slot = scratch.light_slot;
  auto& emission = scratch.emission;
  auto& light_vertex = scratch.light_vertex;
  auto& light_vertex_valid = scratch.light_vertex_valid;
  const std::uint32_t connections = settings_.light_connections;

  for (std::size_t i = 0; i < n; ++i) {
    out[i] = glm::vec3(0.0f);
    state[i] = PathState{};
    active[i] = static_cast<std::uint16_t>(i);
    rays[i] = samples[i].ray;
  }

  // The BSDF sample at vertex sp of path i, the roulette, and the path's next ray (false: the path ends).
  // `scale` is 1 / (the number of continuations the path takes from this vertex); `origin` is
  // leaving_origin(sp) at a non-delta vertex (the only side its BSDF samples), unused at a delta one.
  const auto continue_path = [&](int depth, const SurfacePoint& sp, const glm::vec3& origin, std::uint16_t i,
                                 glm::vec2 u, float scale, Ray& next) {
    PathState& st = state[i];
    BsdfSample bs;
    if (!sp.bsdf().sample(sp.wo, sp.ng, u, bs) || max_component(bs.weight) <= 0.0f) return false;
    st.throughput *= scale == 1.0f ? bs.weight : bs.weight * scale;
    st.eta_scale *= bs.eta_ti * bs.eta_ti;
    st.prev_delta = bs.delta;
    st.prev_bsdf_pdf = bs.pdf;
    st.prev_p = sp.p;
    st.from_split = scale != 1.0f;
    if (st.connection_factor > 0.0f) st.connection_factor *= std::abs(glm::dot(sp.ng, bs.wi));
    // A continuation's throughput carries the 1/splits of its split: the roulette looks at the throughput the
    // path would have unsplit (its survival scale times splits), or it would kill the continuations early
    // and add back the noise the split took off (docs/rendering.md#path-splitting).
    const float roulette_scale = st.split ? st.eta_scale * static_cast<float>(splits) : st.eta_scale;
    if (!survive_roulette(depth, settings_.rr_depth, roulette_scale, st.throughput, samples[i].sampler)) return false;
    if (bs.delta) {
      next = spawn_ray(sp, bs.wi);
    } else {
      next.org = origin;
      next.dir = bs.wi;
      next.tmin = 0.0f;
      next.tmax = std::numeric_limits<float>::infinity();
    }
    return true;
  };

  // Each segment in stages, each stage a loop over the paths: short loop bodies whose iterations are
  // independent, so the core overlaps them. With splitting, a path stops at its first non-delta vertex
  // (after its light sample) and waits there for its continuations: n_split of them, in order of depth.
  std::size_t n_split = 0;
  const auto advance = [&](int first_depth, std::size_t n_active) {
    for (int depth = first_depth; n_active > 0; ++depth) {
      counters.closest_hit_rays += n_active;
      for (std::size_t a = 0; a < n_active; ++a) ctx_.backend->intersect_ids(rays[a], hits[a], counters.query_stats());

      // Hits: escaped radiance, emission, and the vertices that scatter.
      const bool last_segment = settings_.max_depth >= 0 && depth >= settings_.max_depth;
      std::size_t n_vertices = 0;
      for (std::size_t a = 0; a < n_active; ++a) {
        const std::uint16_t i = active[a];
        PathState& st = state[i];
        const Hit& hit = hits[a];
        if (!hit.found()) {
          out[i] += st.throughput * escaped_radiance(ctx_, rays[a].dir, strategy, st.prev_delta, st.prev_bsdf_pdf);
          continue;
        }
        const SurfacePoint sp = make_surface_point(ctx_, rays[a], hit);
        if (depth == 1 && !first.empty()) record_first_hit(&first[i], sp, hit.t);
        // Emission after a delta vertex behind a non-delta first vertex belongs to the light tracer.
        if (sp.geom->emissive && !(st.caustic_by_light_tracer && st.prev_delta))
          out[i] += st.throughput * surface_emission(ctx_, sp, hit, strategy, st.prev_delta, st.prev_bsdf_pdf, st.prev_p,
                                                     st.connection_factor);
        if (last_segment || sp.bsdf().is_black()) continue;
        // A non-delta vertex behind a non-delta one that made light connections: the paths through it compete
        // with those connections (light_connection.h).
        st.connection_factor =
            connections > 0 && !st.prev_delta && !sp.bsdf().is_delta() && depth - 1 <= kLightConnectionMaxDepth
                ? connection_factor(connections, st.from_split ? splits : 1u, st.prev_p, st.prev_bsdf_pdf, sp.p, sp.ng, rays[a].dir)
                : 0.0f;
        vertex[n_vertices] = sp;
        if (!sp.bsdf().is_delta()) vertex_origin[n_vertices] = leaving_origin(sp);
        vertex_path[n_vertices] = i;
        ++n_vertices;
      }

      // Sampler dimensions of a vertex: the light sample (2D; drawn at delta vertices too, unused there, so
      // that every vertex takes the same dimensions), the BSDF sample (2D), the roulette (1D, only once it
      // plays). A vertex that is split keeps its path's sampler as it is after the light sample: each
      // continuation draws the BSDF sample and everything after from its own Sampler::split.
      // With light connections, a first vertex draws its light subpaths' values (a 2D pair each) after its
      // light sample.
      const auto splits_at = [&](std::size_t v) {
        return splits > 1 && !state[vertex_path[v]].split && !vertex[v].bsdf().is_delta();
      };
      const bool trace_light = connections > 0 && depth == 1;
      for (std::size_t v = 0; v < n_vertices; ++v) {
        const std::uint16_t i = vertex_path[v];
        Sampler& sampler = samples[i].sampler;
        u_light[v] = sampler.next_2d();
        if (trace_light) {
          for (std::uint32_t m = 0; m < connections; ++m) {
            u_emit_point[v * connections + m] = sampler.next_2d();
            u_emit_dir[v * connections + m] = sampler.next_2d();
          }
        }
        if (splits_at(v)) split_sampler[i].emplace(sampler);
        u_bsdf[v] = sampler.next_2d();
      }

      // Light samples at the non-delta vertices.
      std::size_t n_shadow = 0;
      for (std::size_t v = 0; v < n_vertices; ++v) {
        if (vertex[v].bsdf().is_delta()) continue;
        ShadowQuery q;
        const std::uint16_t i = vertex_path[v];
        if (!prepare_direct_light(ctx_, vertex[v], vertex_origin[v], strategy, u_light[v], q, state[i].connection_factor))
          continue;
        shadow_rays[n_shadow] = q.ray;
        shadow_contribution[n_shadow] = state[i].throughput * q.contribution;
        shadow_owner[n_shadow] = i;
        ++n_shadow;
      }

      // Light subpaths, traced at the first vertices: the emission samples, then their rays to the first hits.
      if (trace_light) {
        std::size_t n_light = 0;
        for (std::size_t v = 0; v < n_vertices; ++v) {
          const std::uint16_t i = vertex_path[v];
          for (std::uint32_t m = 0; m < connections; ++m) {
            const std::size_t slot = i * connections + m;
            light_vertex_valid[slot] = false;
            EmissionSample& es = emission[slot];
            if (!ctx_.lights->sample_emission(u_emit_point[v * connections + m], u_emit_dir[v * connections + m], es))
              continue;
            Ray& r = light_rays[n_light];
            r.org = offset_ray_origin(es.point, es.normal, es.error_scale);
            r.dir = es.dir;
            r.tmin = 0.0f;
            r.tmax = std::numeric_limits<float>::infinity();
            light_slot[n_light] = static_cast<std::uint32_t>(slot);
            ++n_light;
          }
        }
        counters.closest_hit_rays += n_light;
        for (std::size_t l = 0; l < n_light; ++l)
          ctx_.backend->intersect_ids(light_rays[l], light_hits[l], counters.query_stats());
        for (std::size_t l = 0; l < n_light; ++l) {
          const Hit& hit = light_hits[l];
          if (!hit.found()) continue;
          const GeomShading& g = ctx_.geoms[hit.geom_id];
          if (g.bsdf.is_delta() || g.bsdf.is_black()) continue;
          const std::uint32_t slot = light_slot[l];
          light_vertex[slot] = make_light_vertex(ctx_, emission[slot], make_surface_point(ctx_, light_rays[l], hit), connections);
          light_vertex_valid[slot] = true;
        }
      }

      // Light connections at the non-delta vertices: a shadow ray to each of the path's light vertices (after
      // the vertices' light samples, as alone). A connection at the vertex reached by `depth` segments makes
      // paths of depth + 2.
      if (connections > 0 && depth <= kLightConnectionMaxDepth && (settings_.max_depth < 0 || depth + 2 <= settings_.max_depth)) {
        for (std::size_t v = 0; v < n_vertices; ++v) {
          if (vertex[v].bsdf().is_delta()) continue;
          const std::uint16_t i = vertex_path[v];
          const std::uint32_t pt_count = splits_at(v) ? splits : 1u;
          for (std::uint32_t m = 0; m < connections; ++m) {
            const std::size_t slot = i * connections + m;
            if (!light_vertex_valid[slot]) continue;
            ShadowQuery q;
            if (!prepare_light_connection(vertex[v], vertex_origin[v], state[i].throughput, light_vertex[slot], connections,
                                          pt_count, q))
              continue;
            shadow_rays[n_shadow] = q.ray;
            shadow_contribution[n_shadow] = q.contribution;
            shadow_owner[n_shadow] = i;
            ++n_shadow;
          }
        }
      }

      // BSDF samples, roulette, the next segment's rays.
      std::size_t n_next = 0;
      for (std::size_t v = 0; v < n_vertices; ++v) {
        const SurfacePoint& sp = vertex[v];
        const std::uint16_t i = vertex_path[v];
        if (depth == 1) state[i].caustic_by_light_tracer = settings_.light_traced_caustics && !sp.bsdf().is_delta();
        if (splits_at(v)) {
          state[i].split = true;
          split_vertex[n_split] = sp;
          split_origin[n_split] = vertex_origin[v];
          split_path[n_split] = i;
          split_depth[n_split] = depth;
          split_state[n_split] = state[i];
          ++n_split;
          continue;
        }
        if (!continue_path(depth, sp, vertex_origin[v], i, u_bsdf[v], 1.0f, rays[n_next])) continue;
        active[n_next] = i;
        ++n_next;
      }

      // The light samples of this segment, added before the next segment's emission as a lone path would.
      counters.shadow_rays += n_shadow;
      for (std::size_t k = 0; k < n_shadow; ++k)
        if (!ctx_.backend->occluded(shadow_rays[k], counters.query_stats())) out[shadow_owner[k]] += shadow_contribution[k];
      n_active = n_next;
    }
  };

  advance(1, n);
  // Splitting: continuation j of every split vertex, one after the other, each carrying 1/splits of the
  // vertex's throughput, the vertices reached by the same number of segments together. A path adds its
  // contributions in the same order whether traced alone or in the chunk: the segments up to its split
  // vertex, then continuation 0's, 1's, ...
  const float split_scale = 1.0f / static_cast<float>(splits);
  for (std::uint32_t j = 0; j < splits && n_split > 0; ++j) {
    for (std::size_t group = 0; group < n_split;) {
      const int depth = split_depth[group];
      std::size_t end = group, n_next = 0;
      for (; end < n_split && split_depth[end] == depth; ++end) {
        const std::uint16_t i = split_path[end];
        Sampler& sampler = samples[i].sampler;
        sampler = split_sampler[i]->split(j, splits);
        state[i] = split_state[end];
        if (!continue_path(depth, split_vertex[end], split_origin[end], i, sampler.next_2d(), split_scale, rays[n_next]))
          continue;
        active[n_next] = i;
        ++n_next;
      }
      advance(depth + 1, n_next);
      group = end;
    }
  }
}

}  // namespace twinray
