// twinray converge: error against run time for backends and sampling strategies. Contract in docs/cli.md.

#include "backends/registry.h"
#include "cli/commands.h"
#include "harness/converge/converge_output.h"
#include "harness/converge/convergence_study.h"
#include "harness/converge/peer_series.h"
#include "harness/compare/mitsuba_peer.h"
#include "harness/converge/reference_cache.h"
#include "core/image/image_io.h"
#include "core/scene/scene_loader.h"
#include "core/util/atomic_file.h"

#include <fmt/core.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>

namespace twinray::cli {

namespace {

struct ConvergeCommandOptions {
  std::string scene;
  std::string reference;
  std::optional<int> reference_spp;
  std::string backends = "bvh8,embree";
  std::string strategies = "mis,bsdf,light";
  double budget_seconds = 10.0;
  std::string out;
  std::optional<std::uint64_t> seed;
  int threads = 0;
  std::string peer;  // "mitsuba": add Mitsuba's curve
};

constexpr int kDefaultReferenceSpp = 1024;
// A rendered reference has noise of its own: with study points up to spp = reference_spp / 8, the
// reference's variance is at most 1/8 of the render's, so the error curve stays within ~12% of the true
// one and the slope is not flattened by the reference's noise floor.
constexpr int kReferenceSppRatio = 8;
// With a reference given as a file (converged elsewhere), doubling stops only at the budget.
constexpr int kMaxStudySpp = 1 << 16;

Image rgb_of(const Image& img) {
  if (img.channels == 3) return img;
  Image out(img.width, img.height, 3);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = img.at(x, y, std::min(c, img.channels - 1));
  return out;
}

int run_converge(const ConvergeCommandOptions& opt) {
  converge::StudySettings settings;
  try {
    settings.strategies = converge::parse_strategies(opt.strategies);
    settings.backends = parse_backend_list(opt.backends);
  } catch (const std::invalid_argument& e) {
    return report_bad_input("converge", e.what());
  }
  if (!(opt.budget_seconds > 0.0)) return report_bad_input("converge", "--budget must be positive");
  if (!opt.reference.empty() && opt.reference_spp) return report_bad_input("converge", "--reference and --reference-spp are exclusive");
  if (opt.reference_spp && *opt.reference_spp < 1) return report_bad_input("converge", "--reference-spp must be at least 1");
  if (opt.threads < 0) return report_bad_input("converge", "--threads must be positive (0 = all cores)");
  if (!opt.peer.empty() && opt.peer != "mitsuba") return report_bad_input("converge", "unknown --peer '" + opt.peer + "' (expected mitsuba)");
  if (!opt.peer.empty()) {
    std::string why;
    if (!compare::probe_mitsuba(&why)) return report_bad_input("converge", why);
  }

  const Scene scene = load_scene(opt.scene);
  for (const converge::StrategySpec& s : settings.strategies)
    if (s.needs_environment_map && scene.environment.type != EnvironmentType::Image)
      return report_bad_input("converge", "strategy '" + s.name + "' compares environment sampling, but " + opt.scene +
                       " has no environment map");
  settings.budget_seconds = opt.budget_seconds;
  settings.max_depth = scene.render.max_depth;
  settings.rr_depth = scene.render.rr_depth;
  settings.seed = opt.seed.value_or(scene.render.seed);

  std::optional<tbb::global_control> thread_limit;
  if (opt.threads > 0)
    thread_limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(opt.threads));

  converge::StudyDescription study;
  study.scene = opt.scene;
  study.threads = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  Image reference;
  if (!opt.reference.empty()) {
    reference = rgb_of(read_image(opt.reference));
    if (reference.width != scene.camera.width || reference.height != scene.camera.height)
      return report_bad_input("converge", fmt::format("{}: reference is {}x{}, the scene renders {}x{}", opt.reference, reference.width,
                                   reference.height, scene.camera.width, scene.camera.height));
    study.reference = opt.reference;
    settings.max_spp = kMaxStudySpp;
  } else {
    converge::ReferenceSettings rs;
    rs.spp = opt.reference_spp.value_or(kDefaultReferenceSpp);
    rs.max_depth = settings.max_depth;
    rs.rr_depth = settings.rr_depth;
    rs.seed = settings.seed + converge::kReferenceSeedOffset;
    const std::filesystem::path cached = converge::cached_reference_path(scene, rs);
    study.reference = cached.string();
    study.reference_cached = true;
    study.reference_spp = rs.spp;
    if (std::filesystem::exists(cached)) {
      fmt::print("reference    {} (cached)\n", cached.string());
      reference = rgb_of(read_image(cached));
    } else {
      fmt::print("reference    rendering {} spp with {} into {}\n", rs.spp, converge::kReferenceBackend, cached.string());
      std::fflush(stdout);
      const converge::StrategySpec mis{"mis", SamplingStrategy::Mis, true, false};
      reference = converge::render_image(scene, converge::kReferenceBackend, mis, rs.spp, rs.max_depth, rs.rr_depth, rs.seed,
                                         &study.reference_seconds);
      std::filesystem::create_directories(cached.parent_path());
      write_exr(cached, reference);
      std::filesystem::path sidecar = cached;
      sidecar.replace_extension(".json");
      const nlohmann::json j = {{"scene", std::filesystem::absolute(opt.scene).string()}, {"backend", converge::kReferenceBackend}, {"spp", rs.spp},
                                {"max_depth", rs.max_depth}, {"rr_depth", rs.rr_depth}, {"seed", rs.seed},
                                {"backend", "embree"}, {"strategy", "mis"}, {"version", converge::kReferenceVersion},
                                {"seconds", study.reference_seconds}};
      write_file_atomically(sidecar, j.dump(2) + "\n");
    }
    settings.max_spp = std::max(1, rs.spp / kReferenceSppRatio);
  }
  study.settings = settings;

  const std::filesystem::path out = opt.out.empty() ? std::filesystem::path("converge-" + std::filesystem::path(opt.scene).stem().string())
                                                    : std::filesystem::path(opt.out);
  auto log_point = [](const std::string& line) {
    fmt::print("point        {}\n", line);
    std::fflush(stdout);
  };
  std::vector<converge::ConvergeSeries> series = converge::run_study(scene, reference, settings, log_point);
  if (opt.peer == "mitsuba")
    series.push_back(converge::mitsuba_series(scene, reference, settings, out / "mitsuba",
                                              static_cast<int>(study.threads), log_point));
  const bool plotted = converge::write_study_outputs(out, study, series, reference);
  for (const converge::ConvergeSeries& s : series)
    fmt::print("slope        {:<24} {}\n", converge::series_label(s),
               s.rel_mse_fit.valid() ? fmt::format("{:.3f} (relMSE vs time), {:.3f} (vs spp)", s.rel_mse_fit.slope,
                                                   s.rel_mse_spp_fit.slope)
                                     : std::string("n/a (fewer than two points)"));
  if (!plotted) fmt::print("plot         skipped: gnuplot not found (install gnuplot-nox)\n");
  fmt::print("wrote        {}\n", out.string());
  return kExitOk;
}

}  // namespace

void add_converge_command(CLI::App& app, CommandRunner& run) {
  auto opt = std::make_shared<ConvergeCommandOptions>();
  CLI::App* cmd = app.add_subcommand("converge", "Error against render time per backend and sampling strategy (docs/cli.md).");
  cmd->add_option("scene", opt->scene, "Scene (.json) or bare mesh (.obj, .ply)")->required();
  cmd->add_option("--reference", opt->reference, "Reference image (EXR) of the scene's resolution");
  cmd->add_option("--reference-spp", opt->reference_spp,
                  "Render (and cache) a reference with embree at this spp (default 1024)");
  cmd->add_option("--backends", opt->backends, "Comma-separated backends")->capture_default_str();
  cmd->add_option("--strategies", opt->strategies, "Comma-separated: mis, bsdf, light, env-uniform, env-importance")
      ->capture_default_str();
  cmd->add_option("--budget", opt->budget_seconds, "Seconds of rendering per backend and strategy")->capture_default_str();
  cmd->add_option("--out", opt->out, "Output folder (default converge-SCENE-STEM)");
  cmd->add_option("--seed", opt->seed, "Random seed (default: the scene's render.seed)");
  cmd->add_option("--threads", opt->threads, "Worker threads (0 = all cores)")->capture_default_str();
  cmd->add_option("--peer", opt->peer, "Also plot a peer renderer's curve: mitsuba (docs/mitsuba.md)");
  cmd->callback([opt, &run] { run = [opt] { return run_converge(*opt); }; });
}

}  // namespace twinray::cli
