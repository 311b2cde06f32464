#pragma once
// Rendering an image: setup (what the scene needs), then tiles of pixels rendered in parallel.
//
// Determinism: sample s of pixel p draws all its random numbers from Rng::keyed(seed, p, s), and each
// pixel's samples are accumulated in sample order by whichever thread owns its tile, so the image does not
// depend on the thread count, on tile scheduling, or on whether it was rendered in one pass (--spp) or in
// passes of one sample (--time). Backends that return identical hits give identical images.
//
// Leaving out what a scene does not need: the setup builds environment sampling tables only for an
// environment map, a light sampler only when something emits, and sphere light code only for emissive
// spheres; RenderFeatures records what was built and why the rest was left out. The caustic light tracer
// (core/render/light_tracer.h) runs only for the path integrator on scenes with a delta BSDF (mirror,
// glass) and a surface light, unless RenderOptions::caustics is Off.

#include "core/backend/backend.h"
#include "core/lights/area_lights.h"
#include "core/lights/environment_light.h"
#include "core/render/film.h"
#include "core/render/integrator.h"
#include "core/scene/scene.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace twinray {

// Whether caustics seen directly on diffuse surfaces are light traced (core/render/light_tracer.h).
enum class CausticsMode { Auto, Off };
std::string_view to_string(CausticsMode m);
std::optional<CausticsMode> parse_caustics_mode(std::string_view name);

struct RenderOptions {
  IntegratorKind integrator = IntegratorKind::Path;
  IntegratorSettings settings;
  bool env_importance_sampling = true;  // false: uniform directions (convergence studies)
  int spp = 16;
  double time_budget_seconds = 0.0;     // > 0: passes of 1 spp until the time is used (spp ignored)
  std::uint64_t seed = 0;
  AuxChannels aux;
  SamplerKind sampler = SamplerKind::Sobol4d;  // core/sampling/sampler.h
  CausticsMode caustics = CausticsMode::Auto;
  int tile_size = 16;
  bool show_progress = true;            // a progress line on a terminal (core/util/progress.h)
};

struct FeatureNote {
  std::string name;
  bool used = false;
  std::string reason;  // why it was left out (empty when used)
};

struct RenderFeatures {
  bool environment = false;          // rays that escape see radiance
  bool env_sampling_tables = false;  // importance tables of an environment map were built
  bool light_sampler = false;        // next-event estimation possible
  bool sphere_lights = false;        // sphere light sampling code in use
  bool sphere_geometry = false;      // the scene has spheres at all
  bool traversal_cost = false;       // the cost AOV is recorded
  bool caustic_light_tracing = false;  // light paths through specular chains are connected to the camera
  std::size_t triangle_light_count = 0;
  std::size_t sphere_light_count = 0;
  std::vector<FeatureNote> notes;    // human-readable, in summary order

  std::vector<std::string> used() const;
  std::vector<std::string> left_out() const;  // "name (reason)"
};

// What a scene needs for rendering, built once: the environment light, the light sampler and the notes.
class RenderSetup {
 public:
  // The scene must outlive the setup (and every render using it). `backend_traits` only informs the cost
  // feature (traits().counts_traversal). Reads the environment map: throws InputError when it is bad.
  RenderSetup(const Scene& scene, const RenderOptions& options, const BackendTraits& backend_traits);

  const Scene& scene() const { return *scene_; }
  const RenderFeatures& features() const { return features_; }
  const EnvironmentLight* environment() const { return environment_.get(); }
  const LightSampler* lights() const { return lights_ ? &*lights_ : nullptr; }
  const RenderOptions& options() const { return options_; }

 private:
  const Scene* scene_;
  RenderOptions options_;
  std::unique_ptr<EnvironmentLight> environment_;
  std::optional<LightSampler> lights_;
  RenderFeatures features_;
};

struct RenderStats {
  double seconds = 0.0;
  int spp = 0;                          // samples per pixel actually rendered
  std::uint64_t samples = 0;            // camera samples
  std::uint64_t closest_hit_rays = 0;   // camera, continuation and light-path rays
  std::uint64_t shadow_rays = 0;       // light samples and camera connections
  std::uint64_t nonfinite_samples = 0;  // NaN/Inf radiance: replaced by 0, counted here
  std::uint64_t negative_samples = 0;   // a negative component: clamped to 0, counted here
  std::uint64_t light_paths = 0;        // caustic light tracer: paths started (one per camera sample)
  std::uint64_t splats = 0;             // and their connections to the camera that reached the film
  std::uint64_t nonfinite_splats = 0;   // NaN/Inf connections: dropped, counted here
  QueryStats query;                     // traversal cost (only with the cost AOV)

  std::uint64_t rays() const { return closest_hit_rays + shadow_rays; }
  double samples_per_second() const { return seconds > 0.0 ? static_cast<double>(samples) / seconds : 0.0; }
  double rays_per_second() const { return seconds > 0.0 ? static_cast<double>(rays()) / seconds : 0.0; }
};

struct RenderResult {
  Film film;
  RenderStats stats;
};

// Renders with the current TBB concurrency (limit it with tbb::global_control). The backend must be built.
RenderResult render(const RenderSetup& setup, const Backend& backend);

std::unique_ptr<Integrator> make_integrator(IntegratorKind kind, const SceneContext& ctx,
                                            const IntegratorSettings& settings);

}  // namespace twinray
