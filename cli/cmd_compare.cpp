// twinray compare: the same scene rendered by twinray and by a peer renderer (Mitsuba 3), with a verdict on
// whether they agree within noise. Contract in docs/cli.md, statistics in harness/compare/image_comparison.h.

#include "backends/registry.h"
#include "cli/commands.h"
#include "harness/compare/compare_run.h"
#include "core/scene/scene_loader.h"
#include "core/util/atomic_file.h"

#include <fmt/core.h>
#include <tbb/global_control.h>

#include <cstdio>
#include <memory>
#include <optional>

namespace twinray::cli {

namespace {

struct CompareCommandOptions {
  std::string scene;
  std::string peer = "mitsuba";
  std::optional<int> spp;
  std::optional<double> time_seconds;
  int batches = 8;
  std::string backend = "bvh8";  // render's default
  std::optional<std::uint64_t> seed;
  int threads = 0;
  std::optional<int> rr_depth;
  std::string caustics = "auto";
  std::optional<std::uint32_t> splits;
  std::optional<std::uint32_t> light_connections;
  std::string variant = "auto";
  std::string reference;
  std::string out;
  std::string json;
};

std::string fmt_means(const compare::ChannelMeans& m) {
  return fmt::format("({:.5f} ± {:.5f}, {:.5f} ± {:.5f}, {:.5f} ± {:.5f})", m.mean[0], m.standard_error[0], m.mean[1],
                     m.standard_error[1], m.mean[2], m.standard_error[2]);
}

int run_compare_command(const CompareCommandOptions& opt) {
  if (opt.peer != "mitsuba") return report_bad_input("compare", "unknown --peer '" + opt.peer + "' (expected mitsuba)");
  if (opt.spp && opt.time_seconds) return report_bad_input("compare", "--spp and --time are exclusive");
  if (opt.spp && *opt.spp < 1) return report_bad_input("compare", "--spp must be at least 1");
  if (opt.time_seconds && !(*opt.time_seconds > 0.0)) return report_bad_input("compare", "--time must be positive");
  if (opt.batches < 2 || opt.batches > 1024) return report_bad_input("compare", "--batches must be 2 to 1024 (the variance comes from them)");
  if (opt.threads < 0) return report_bad_input("compare", "--threads must be positive (0 = all cores)");
  if (opt.variant != "auto" && opt.variant != "llvm_ad_rgb" && opt.variant != "scalar_rgb")
    return report_bad_input("compare", "unknown --variant '" + opt.variant + "' (auto, llvm_ad_rgb or scalar_rgb)");
  try {
    (void)parse_backend_list(opt.backend);
  } catch (const std::invalid_argument& e) {
    return report_bad_input("compare", e.what());
  }
  const std::optional<CausticsMode> caustics = parse_caustics_mode(opt.caustics);
  if (!caustics) return report_bad_input("compare", "unknown --caustics '" + opt.caustics + "' (choose from auto, off)");
  if (opt.splits && (*opt.splits < 1 || *opt.splits > kMaxSplits))
    return report_bad_input("compare", "--splits must be between 1 and " + std::to_string(kMaxSplits));
  if (opt.light_connections && *opt.light_connections > kMaxLightConnections)
    return report_bad_input("compare", "--light-connections must be between 0 and " + std::to_string(kMaxLightConnections));
  std::string why;
  if (!compare::probe_mitsuba(&why)) return report_bad_input("compare", why);

  const Scene scene = load_scene(opt.scene);
  compare::CompareSettings s;
  s.peer = opt.peer;
  s.spp = opt.spp.value_or(scene.render.spp);
  if (s.spp < opt.batches) s.spp = opt.batches;  // at least one sample per batch
  s.time_seconds = opt.time_seconds.value_or(0.0);
  s.batches = opt.batches;
  s.backend = opt.backend;
  s.seed = opt.seed.value_or(scene.render.seed);
  s.threads = opt.threads;
  s.rr_depth = opt.rr_depth.value_or(scene.render.rr_depth);
  s.caustics = *caustics;
  if (opt.splits) s.splits = *opt.splits;
  if (opt.light_connections) s.light_connections = *opt.light_connections;
  s.mitsuba_variant = opt.variant;
  s.reference = opt.reference;
  s.out = opt.out.empty() ? std::filesystem::path("compare-" + std::filesystem::path(opt.scene).stem().string())
                          : std::filesystem::path(opt.out);

  std::optional<tbb::global_control> thread_limit;
  if (opt.threads > 0)
    thread_limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(opt.threads));
  s.threads = static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));

  const compare::CompareResult r = compare::run_compare(scene, opt.scene, s, [](const std::string& line) {
    fmt::print("{}\n", line);
    std::fflush(stdout);
  });
  const compare::Comparison& c = r.comparison;
  for (const compare::RendererResult* x : {&r.twinray, &r.peer}) {
    fmt::print("{:<12} {} ({} spp in {} batches, {:.3f} s)\n", x->name, x->variant, x->spp, x->batches, x->seconds);
    fmt::print("  means      {}\n", fmt_means(x->means));
    fmt::print("  relMSE     {:.4e} ({}; its noise explains {:.4e})\n", x->rel_mse,
               r.has_reference ? "against the reference" : "noise estimate, no reference", x->rel_mse_from_noise);
    fmt::print("  time x relMSE {:.4e}\n", x->seconds * x->rel_mse);
  }
  if (r.json.contains("efficiency_ratio") && !r.json["efficiency_ratio"].is_null())
    fmt::print("efficiency   twinray's time x relMSE is {:.3f} x {}'s\n", r.json["efficiency_ratio"].get<double>(),
               r.peer.name);
  fmt::print("between      relMSE {:.4e}, noise explains {:.4e}, excess {:.3e}\n", c.rel_mse_between,
             c.rel_mse_between_noise, c.rel_mse_excess());
  fmt::print("regions      {} ({}x{} grid x RGB), largest |z| {:.2f}, threshold {:.2f}\n", c.regions.size(),
             compare::kRegionGrid, compare::kRegionGrid, c.max_abs_z, c.threshold);
  std::size_t shown = 0;
  for (const compare::RegionDifference& d : c.differing) {
    if (++shown > 10) break;
    fmt::print("  differs    pixels [{}, {}) x [{}, {}) channel {}: {:+.5f} ± {:.5f} (z {:+.1f})\n", d.x0, d.x1, d.y0,
               d.y1, "RGB"[d.channel], d.difference, d.standard_error, d.z);
  }
  fmt::print("verdict      {}\n", c.agree ? "agree (within noise)" : fmt::format("differ ({} region-channels)", c.differing.size()));
  fmt::print("wrote        {}\n", s.out.string());
  if (!opt.json.empty()) write_file_atomically(opt.json, r.json.dump(2) + "\n");
  return c.agree ? kExitOk : kExitCheckFailed;
}

}  // namespace

void add_compare_command(CLI::App& app, CommandRunner& run) {
  auto opt = std::make_shared<CompareCommandOptions>();
  CLI::App* cmd = app.add_subcommand("compare", "Render a scene with twinray and with Mitsuba 3 and say whether they agree within noise (docs/mitsuba.md)");
  cmd->add_option("scene", opt->scene, "Scene (.json, .xml) or bare mesh (.obj, .ply)")->required();
  cmd->add_option("--peer", opt->peer, "Peer renderer: mitsuba")->capture_default_str();
  cmd->add_option("--spp", opt->spp, "Samples per pixel for each renderer (default: the scene's)");
  cmd->add_option("--time", opt->time_seconds, "Render time in seconds for each renderer instead of --spp");
  cmd->add_option("--batches", opt->batches, "Independent batches per renderer (the variance comes from them)")->capture_default_str();
  cmd->add_option("--backend", opt->backend, "twinray's backend")->capture_default_str();
  cmd->add_option("--seed", opt->seed, "Seed (default: the scene's render.seed)");
  cmd->add_option("--threads", opt->threads, "Worker threads of both renderers (0 = all cores)")->capture_default_str();
  cmd->add_option("--rr-depth", opt->rr_depth, "Russian roulette depth of both renderers (default: the scene's)");
  cmd->add_option("--splits", opt->splits, "twinray's path continuations from each first non-delta vertex, 1 to 16 "
                                           "(as render --splits; default: render's)");
  cmd->add_option("--light-connections", opt->light_connections,
                  "twinray's light subpaths per camera sample joined to its camera paths, 0 to 4 (as render "
                  "--light-connections; default: render's)");
  cmd->add_option("--caustics", opt->caustics, "twinray's caustic light tracing: auto or off (docs/rendering.md)")
      ->capture_default_str();
  cmd->add_option("--variant", opt->variant, "Mitsuba variant: auto (llvm_ad_rgb, else scalar_rgb), llvm_ad_rgb, scalar_rgb")->capture_default_str();
  cmd->add_option("--reference", opt->reference, "Reference image: relMSE of both renders against it");
  cmd->add_option("--out", opt->out, "Output folder (default compare-SCENE-STEM)");
  cmd->add_option("--json", opt->json, "Also copy compare.json to this file");
  cmd->callback([opt, &run] { run = [opt] { return run_compare_command(*opt); }; });
}

}  // namespace twinray::cli
