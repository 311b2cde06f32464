#pragma once
// `twinray compare SCENE --peer mitsuba`: the same scene rendered by twinray and by Mitsuba 3, and whether
// the two images agree within their noise (harness/compare/image_comparison.h).
//
// Both renderers render `batches` independent batches (different seeds) of spp / batches samples, so both
// images come with a per-pixel variance measured the same way. Times are render times only: twinray's
// excludes scene loading and the BVH build, Mitsuba's excludes loading (its BVH build) and one warm-up
// render that compiles its kernels.
//
// Output folder: twinray.{exr,png}, mitsuba.{exr,png}, difference.png (per-pixel |twinray - mitsuba| in
// standard errors, false colour 0..4), regions.png (per-region |z|, false colour 0 .. 2 x threshold: bright
// = differ), compare.json, and mitsuba/ (the exported scene and Mitsuba's log).

#include "harness/compare/image_comparison.h"
#include "harness/compare/mitsuba_peer.h"
#include "core/render/renderer.h"
#include "core/scene/scene.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace twinray::compare {

struct CompareSettings {
  std::string peer = "mitsuba";
  int spp = 0;                     // total samples per pixel (0: the scene's render.spp)
  double time_seconds = 0.0;       // > 0: each renderer renders for about this long instead of spp
  int batches = 8;
  std::string backend = "bvh8";  // render's default
  std::uint64_t seed = 0;
  int threads = 0;                 // 0 = all cores
  int rr_depth = 5;
  CausticsMode caustics = CausticsMode::Auto;  // twinray's caustic light tracer (core/render/renderer.h)
  std::uint32_t splits = IntegratorSettings{}.splits;  // twinray's path splitting (core/render/integrator.h)
  std::uint32_t light_connections = IntegratorSettings{}.light_connections;  // twinray's light connections (same)
  std::string mitsuba_variant = "auto";
  std::filesystem::path reference; // optional: relMSE of both against it
  std::filesystem::path out;       // output folder
};

struct RendererResult {
  std::string name;     // "twinray" or "mitsuba"
  std::string variant;  // twinray: backend and sampler; mitsuba: its variant (llvm_ad_rgb, scalar_rgb)
  NoisyImage image;
  ChannelMeans means;
  double seconds = 0.0;
  int spp = 0;
  int batches = 0;
  double rel_mse = 0.0;             // against the reference, or the noise estimate without one
  double rel_mse_from_noise = 0.0;  // what its noise alone explains (against the reference or the mean of both)
  nlohmann::json extra;             // renderer-specific figures
};

struct CompareResult {
  RendererResult twinray, peer;
  Comparison comparison;
  bool has_reference = false;
  nlohmann::json json;  // what compare.json holds
};

// Renders with twinray (in-process) and the peer, compares, writes the output folder. Throws
// MitsubaUnavailable when Mitsuba is not installed, InputError for a bad reference.
CompareResult run_compare(const Scene& scene, const std::filesystem::path& scene_path, const CompareSettings& settings,
                          const std::function<void(const std::string&)>& log);

// twinray's half alone: `batches` renders of spp / batches samples (or time_seconds / batches each) with
// seeds seed, seed + 1, ...; mean, variance of the mean from the batches, summed render seconds.
RendererResult render_twinray_batches(const Scene& scene, const CompareSettings& settings);

// The JSON document of a comparison (documented in docs/cli.md).
nlohmann::json compare_json(const CompareResult& r, const std::filesystem::path& scene_path,
                            const CompareSettings& settings);

}  // namespace twinray::compare
