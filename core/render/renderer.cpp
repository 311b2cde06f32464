#include "core/render/renderer.h"

#include "core/camera/pinhole_camera.h"
#include "core/render/direct_integrator.h"
#include "core/render/light_tracer.h"
#include "core/render/path_integrator.h"
#include "core/render/light_transport.h"
#include "core/sampling/rng.h"
#include "core/util/fp_mode.h"
#include "core/util/progress.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>

namespace twinray {

std::string_view to_string(IntegratorKind k) { return k == IntegratorKind::Direct ? "direct" : "path"; }

std::string_view to_string(SamplingStrategy s) {
  switch (s) {
    case SamplingStrategy::Mis: return "mis";
    case SamplingStrategy::Bsdf: return "bsdf";
    case SamplingStrategy::Light: return "light";
  }
  return "mis";
}

std::string_view to_string(CausticsMode m) { return m == CausticsMode::Off ? "off" : "auto"; }

std::optional<CausticsMode> parse_caustics_mode(std::string_view name) {
  if (name == "auto") return CausticsMode::Auto;
  if (name == "off") return CausticsMode::Off;
  return std::nullopt;
}

std::vector<std::string> RenderFeatures::used() const {
  std::vector<std::string> out;
  for (const FeatureNote& n : notes)
    if (n.used) out.push_back(n.name);
  return out;
}

std::vector<std::string> RenderFeatures::left_out() const {
  std::vector<std::string> out;
  for (const FeatureNote& n : notes)
    if (!n.used) out.push_back(n.name + " (" + n.reason + ")");
  return out;
}

RenderSetup::RenderSetup(const Scene& scene, const RenderOptions& options, const BackendTraits& backend_traits)
    : scene_(&scene), options_(options) {
  RenderFeatures& f = features_;
  environment_ = EnvironmentLight::create(scene.environment, options.env_importance_sampling);
  f.environment = environment_ != nullptr;
  f.env_sampling_tables = environment_ && environment_->has_sampling_tables();

  const bool wants_light_sampling = options.settings.strategy != SamplingStrategy::Bsdf;
  if (wants_light_sampling && (scene.has_emitters() || environment_)) {
    lights_.emplace(scene, environment_.get());
    if (lights_->empty()) lights_.reset();
  }
  f.light_sampler = lights_.has_value();
  f.triangle_light_count = lights_ ? lights_->triangle_count() : 0;
  f.sphere_light_count = lights_ ? lights_->sphere_count() : 0;
  f.sphere_lights = f.sphere_light_count > 0;
  f.sphere_geometry = scene.geometry.has_spheres();
  f.traversal_cost = options.aux.cost && backend_traits.counts_traversal;

  auto note = [&f](std::string name, bool used, std::string reason) {
    f.notes.push_back({std::move(name), used, used ? std::string() : std::move(reason)});
  };
  note("environment", f.environment, "no environment");
  if (!f.environment) {
    note("env sampling tables", false, "no environment");
  } else if (environment_->is_constant()) {
    note("env sampling tables", false, "constant environment needs none");
  } else {
    note("env sampling tables", f.env_sampling_tables, "uniform environment sampling requested");
  }
  if (!wants_light_sampling) {
    note("light sampling", false, "bsdf-only strategy");
  } else {
    note("light sampling", f.light_sampler, "no emitters");
  }
  note("sphere code paths", f.sphere_geometry, "no spheres");
  if (f.sphere_geometry) note("sphere light sampling", f.sphere_lights, "no emissive spheres");
  if (options.aux.cost)
    note("traversal cost", f.traversal_cost, "backend does not count traversal");

  const bool has_delta_bsdf = std::any_of(scene.shapes.begin(), scene.shapes.end(), [&scene](const ShapeInfo& s) {
    const MaterialType t = scene.materials[s.material].type;
    return t == MaterialType::Mirror || t == MaterialType::Glass;
  });
  const bool surface_lights = lights_ && lights_->has_surface_lights();
  f.caustic_light_tracing = options.caustics == CausticsMode::Auto && options.integrator == IntegratorKind::Path &&
                            has_delta_bsdf && surface_lights;
  std::string caustics_reason;
  if (options.caustics == CausticsMode::Off) caustics_reason = "--caustics off";
  else if (options.integrator != IntegratorKind::Path) caustics_reason = "direct integrator";
  else if (!has_delta_bsdf) caustics_reason = "no mirror or glass";
  else if (!wants_light_sampling) caustics_reason = "bsdf-only strategy";
  else if (!surface_lights) caustics_reason = "no area lights";
  note("caustic light tracing", f.caustic_light_tracing, caustics_reason);
}

std::unique_ptr<Integrator> make_integrator(IntegratorKind kind, const SceneContext& ctx,
                                            const IntegratorSettings& settings) {
  if (kind == IntegratorKind::Direct) return std::make_unique<DirectIntegrator>(ctx, settings);
  return std::make_unique<PathIntegrator>(ctx, settings);
}

namespace {

struct Tile {
  int x0, y0, x1, y1;
};

std::vector<Tile> make_tiles(int width, int height, int size) {
  std::vector<Tile> tiles;
  for (int y = 0; y < height; y += size)
    for (int x = 0; x < width; x += size)
      tiles.push_back({x, y, std::min(x + size, width), std::min(y + size, height)});
  return tiles;
}

bool finite3(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Tallies of one tile, merged under a mutex once per tile (never per sample).
struct TileTally {
  TraceCounters counters;
  std::uint64_t samples = 0;
  std::uint64_t nonfinite = 0;
  std::uint64_t negative = 0;
};

// Adds one sample's radiance to its pixel (NaN/Inf replaced by 0, negative components clamped, both counted).
void accumulate(Film::PixelSums& px, glm::vec3 L, TileTally& tally) {
  if (!finite3(L)) {
    L = glm::vec3(0.0f);
    ++tally.nonfinite;
  } else if (L.x < 0.0f || L.y < 0.0f || L.z < 0.0f) {
    L = glm::max(L, glm::vec3(0.0f));
    ++tally.negative;
  }
  const glm::dvec3 Ld(L);
  px.sum += Ld;
  px.sum_sq += Ld * Ld;
  ++px.samples;
  ++tally.samples;
}

void accumulate_first_hit(Film& film, std::size_t idx, const FirstHitInfo& first) {
  if (!first.hit) return;
  if (glm::dvec3* n = film.normal_sum(idx)) *n += glm::dvec3(first.normal);
  if (glm::dvec3* a = film.albedo_sum(idx)) *a += glm::dvec3(first.albedo);
  if (double* d = film.depth_sum(idx)) {
    *d += static_cast<double>(first.depth);
    ++*film.depth_hit_count(idx);
  }
}

// Renders samples [sample_begin, sample_end) of every pixel of the tile, one sample of all its pixels at a
// time (the integrator's batch), each pixel's samples added in sample order.
void render_tile(const Tile& tile, int sample_begin, int sample_end, const PinholeCamera& camera,
                 const Integrator& integrator, SamplerKind sampler_kind, std::uint64_t seed, Film& film,
                 TileTally& tally) {
  const bool want_first = film.aux().normals || film.aux().albedo || film.aux().depth;
  // The cost image needs each sample's own traversal cost: samples are then traced one by one.
  const bool per_sample_cost = film.aux().cost;
  const auto width = static_cast<std::uint64_t>(film.width());
  const std::size_t n = static_cast<std::size_t>(tile.x1 - tile.x0) * static_cast<std::size_t>(tile.y1 - tile.y0);
  std::vector<CameraSample> batch;
  batch.reserve(n);
  std::vector<glm::vec3> radiance(n);
  std::vector<FirstHitInfo> first(want_first ? n : 0);
  std::vector<std::size_t> pixel(n);
  for (int s = sample_begin; s < sample_end; ++s) {
    batch.clear();
    for (int y = tile.y0; y < tile.y1; ++y)
      for (int x = tile.x0; x < tile.x1; ++x) {
        const std::uint64_t pixel_index = static_cast<std::uint64_t>(y) * width + static_cast<std::uint64_t>(x);
        pixel[batch.size()] = static_cast<std::size_t>(pixel_index);
        Sampler sampler(sampler_kind, seed, pixel_index, static_cast<std::uint32_t>(s));
        const glm::vec2 jitter = sampler.next_2d();
        const Ray ray = camera.generate_ray((static_cast<float>(x) + jitter.x) / static_cast<float>(camera.width()),
                                            1.0f - (static_cast<float>(y) + jitter.y) / static_cast<float>(camera.height()));
        batch.push_back(CameraSample{ray, sampler});
      }
    if (want_first) std::fill(first.begin(), first.end(), FirstHitInfo{});
    if (!per_sample_cost) {
      integrator.radiance(std::span(batch), std::span(radiance), std::span(first), tally.counters);
    } else {
      for (std::size_t k = 0; k < n; ++k) {
        const QueryStats before = tally.counters.query;
        const std::uint64_t rays_before = tally.counters.closest_hit_rays + tally.counters.shadow_rays;
        radiance[k] = integrator.radiance(batch[k].ray, batch[k].sampler, tally.counters, want_first ? &first[k] : nullptr);
        const QueryStats& after = tally.counters.query;
        const std::uint64_t rays_after = tally.counters.closest_hit_rays + tally.counters.shadow_rays;
        *film.cost_sum(pixel[k]) += glm::dvec3(static_cast<double>(after.nodes_visited - before.nodes_visited),
                                               static_cast<double>(after.primitives_tested - before.primitives_tested),
                                               static_cast<double>(rays_after - rays_before));
      }
    }
    for (std::size_t k = 0; k < n; ++k) {
      accumulate(film.pixel(pixel[k]), radiance[k], tally);
      if (want_first) accumulate_first_hit(film, pixel[k], first[k]);
    }
  }
}

// Light paths go in chunks of kLightChunk, kRoundChunks chunks traced in parallel at a time; then the
// round's splats are added to the film one chunk after the other, in chunk order, so the sums depend only
// on the light paths' global indices. A round bounds the splat lists' memory (a chunk rarely holds more
// splats than paths) and costs one join of the workers, small next to 2^17 light paths.
constexpr std::uint64_t kLightChunk = 256;
constexpr std::size_t kRoundChunks = 512;

struct LightChunk {
  std::vector<Splat> splats;
  TraceCounters counters;
  std::uint64_t nonfinite = 0;
};

std::uint64_t light_rounds(std::uint64_t paths) {
  const std::uint64_t per_round = kLightChunk * kRoundChunks;
  return (paths + per_round - 1) / per_round;
}

// `progress`, when given, advances by one per round.
void trace_light_paths(const LightTracer& tracer, std::uint64_t begin, std::uint64_t end, bool collect_query_stats,
                       std::vector<LightChunk>& chunks, Film& film, RenderStats& stats, Progress* progress) {
  chunks.resize(kRoundChunks);
  for (std::uint64_t round = begin; round < end; round += kLightChunk * kRoundChunks) {
    const std::uint64_t round_end = std::min(end, round + kLightChunk * kRoundChunks);
    const auto n_chunks = static_cast<std::size_t>((round_end - round + kLightChunk - 1) / kLightChunk);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_chunks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
      ScopedFlushDenormals ftz;
      for (std::size_t c = r.begin(); c != r.end(); ++c) {
        LightChunk& chunk = chunks[c];
        chunk.splats.clear();
        chunk.counters = TraceCounters{};
        chunk.counters.collect_query_stats = collect_query_stats;
        chunk.nonfinite = 0;
        const std::uint64_t first = round + c * kLightChunk;
        tracer.trace(first, std::min(round_end, first + kLightChunk), chunk.splats, chunk.counters, chunk.nonfinite);
      }
    });
    for (std::size_t c = 0; c < n_chunks; ++c) {
      const LightChunk& chunk = chunks[c];
      for (const Splat& s : chunk.splats) film.add_splat(s.pixel, glm::dvec3(s.value));
      stats.splats += chunk.splats.size();
      stats.nonfinite_splats += chunk.nonfinite;
      stats.closest_hit_rays += chunk.counters.closest_hit_rays;
      stats.shadow_rays += chunk.counters.shadow_rays;
      stats.query += chunk.counters.query;
    }
    stats.light_paths += round_end - round;
    if (progress) progress->advance();
  }
}

}  // namespace

RenderResult render(const RenderSetup& setup, const Backend& backend) {
  const RenderOptions& opt = setup.options();
  const Scene& scene = setup.scene();
  const PinholeCamera camera(scene.camera);
  const SceneContext ctx = SceneContext::make(scene, backend, setup.environment(), setup.lights());
  IntegratorSettings settings = opt.settings;
  settings.light_traced_caustics = setup.features().caustic_light_tracing;
  const std::unique_ptr<Integrator> integrator = make_integrator(opt.integrator, ctx, settings);
  std::optional<LightTracer> light_tracer;
  if (settings.light_traced_caustics) light_tracer.emplace(ctx, settings, camera, opt.sampler, opt.seed);
  std::vector<LightChunk> light_chunks;

  AuxChannels aux = opt.aux;
  aux.cost = setup.features().traversal_cost;
  RenderResult result{Film(camera.width(), camera.height(), aux), RenderStats{}};
  if (light_tracer) result.film.enable_splats();
  const std::uint64_t pixel_count = static_cast<std::uint64_t>(camera.width()) * static_cast<std::uint64_t>(camera.height());
  const std::vector<Tile> tiles = make_tiles(camera.width(), camera.height(), std::max(1, opt.tile_size));

  std::mutex merge_mutex;
  RenderStats& stats = result.stats;
  auto run_pass = [&](int sample_begin, int sample_end, Progress* progress) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
      ScopedFlushDenormals ftz;
      for (std::size_t t = r.begin(); t != r.end(); ++t) {
        TileTally tally;
        tally.counters.collect_query_stats = aux.cost;
        render_tile(tiles[t], sample_begin, sample_end, camera, *integrator, opt.sampler, opt.seed, result.film, tally);
        {
          std::lock_guard lock(merge_mutex);
          stats.samples += tally.samples;
          stats.closest_hit_rays += tally.counters.closest_hit_rays;
          stats.shadow_rays += tally.counters.shadow_rays;
          stats.nonfinite_samples += tally.nonfinite;
          stats.negative_samples += tally.negative;
          stats.query += tally.counters.query;
        }
        if (progress) progress->advance();
      }
    });
    // One light path per camera sample: light path i belongs to sample i / P (P pixels), whichever pass.
    if (light_tracer)
      trace_light_paths(*light_tracer, static_cast<std::uint64_t>(sample_begin) * pixel_count,
                        static_cast<std::uint64_t>(sample_end) * pixel_count, aux.cost, light_chunks, result.film, stats,
                        progress);
  };

  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&start] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  if (opt.time_budget_seconds > 0.0) {
    // Passes of one sample per pixel; the progress line counts time, the ETA is the rest of the budget.
    constexpr std::uint64_t kProgressSteps = 1000;
    std::optional<Progress> progress;
    if (opt.show_progress) progress.emplace("render", kProgressSteps);
    std::uint64_t shown = 0;
    int pass = 0;
    do {
      run_pass(pass, pass + 1, nullptr);
      ++pass;
      const auto target = static_cast<std::uint64_t>(
          std::min(1.0, elapsed() / opt.time_budget_seconds) * static_cast<double>(kProgressSteps));
      if (progress && target > shown) {
        progress->advance(target - shown);
        shown = target;
      }
    } while (elapsed() < opt.time_budget_seconds);
    stats.spp = pass;
  } else {
    std::optional<Progress> progress;
    // Tiles, then the light paths' rounds (caustics), which run after the tiles of the pass.
    const std::uint64_t rounds =
        light_tracer ? light_rounds(static_cast<std::uint64_t>(std::max(0, opt.spp)) * pixel_count) : 0;
    if (opt.show_progress) progress.emplace("render", tiles.size() + rounds);
    run_pass(0, std::max(0, opt.spp), progress ? &*progress : nullptr);
    stats.spp = std::max(0, opt.spp);
  }
  stats.seconds = elapsed();
  result.film.set_splat_samples_per_pixel(static_cast<std::uint64_t>(stats.spp));
  return result;
}

}  // namespace twinray
