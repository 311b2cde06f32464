// twinray crosscheck: the same rays through several backends, and a verdict on every disagreement.

#include "backends/registry.h"
#include "cli/commands.h"
#include "harness/crosscheck/crosscheck_run.h"
#include "harness/crosscheck/ray_kinds.h"
#include "core/util/atomic_file.h"

#include <fmt/core.h>
#include <memory>
#include <stdexcept>

namespace twinray::cli {

namespace {

struct CrosscheckOptions {
  std::string scene;
  std::string backends = "bvh8,embree";
  // Signed on purpose: CLI11 would wrap "-5" into a huge unsigned count.
  std::int64_t rays = 100000;
  std::string kinds = "camera,uniform,diffuse,shadow,axis";
  std::uint64_t seed = 1;
  std::string json;
  bool no_arbiter = false;
  bool strict = false;
  std::int64_t arbiter_max_rays = 100000;  // signed for the same reason as rays
};

int run_crosscheck_command(const CrosscheckOptions& opt) {
  crosscheck::CrosscheckSettings settings;
  settings.scene = opt.scene;
  settings.seed = opt.seed;
  try {
    settings.backends = parse_backend_list(opt.backends);
    settings.kinds = crosscheck::parse_ray_kinds(opt.kinds);
  } catch (const std::invalid_argument& e) {
    return report_bad_input("crosscheck", e.what());
  }
  if (settings.backends.size() < 2) {
    return report_bad_input("crosscheck", "--backends needs at least two backends to compare");
  }
  // Each ray costs 32 bytes plus a 40-byte hit and an any-hit flag per backend: 10M rays stay near 1 GB.
  constexpr std::int64_t kMaxRays = 10'000'000;
  if (opt.rays < 1 || opt.rays > kMaxRays) {
    return report_bad_input("crosscheck", fmt::format("--rays must be between 1 and {}, got {}", kMaxRays, opt.rays));
  }
  settings.rays_per_kind = static_cast<std::size_t>(opt.rays);
  if (opt.arbiter_max_rays < 0) {
    return report_bad_input("crosscheck", fmt::format("--arbiter-max-rays must be at least 0, got {}", opt.arbiter_max_rays));
  }
  settings.arbitrate = !opt.no_arbiter;
  settings.strict = opt.strict;
  settings.arbiter_max_rays = static_cast<std::size_t>(opt.arbiter_max_rays);

  const crosscheck::CrosscheckReport report = crosscheck::run_crosscheck(settings);
  fmt::print("{}", report.text);
  if (!opt.json.empty()) write_file_atomically(opt.json, report.json.dump(2) + "\n");
  return report.passed() ? kExitOk : kExitCheckFailed;
}

}  // namespace

void add_crosscheck_command(CLI::App& app, CommandRunner& run) {
  auto opt = std::make_shared<CrosscheckOptions>();
  CLI::App* cmd = app.add_subcommand(
      "crosscheck",
      "Trace the same rays through several backends, classify every disagreement, rule each one against\n"
      "the exact backend (who is right, and why), and judge every backend's u, v and ng on their own.\n"
      "Exit code: 0 no genuine mismatch and no wrong u, v or ng, 1 otherwise (or a plugin failed: crashed, hung,\n"
      "declined the scene), 2 bad input. The arbiter's rulings are reported, and part of the exit code with --strict.");
  cmd->add_option("scene", opt->scene,
                  "Scene (.json), bare mesh (.obj, .ply), $TWINRAY_SHARED/... or procedural:KIND[:ARG]...")
      ->required();
  cmd->add_option("--backends", opt->backends,
                  "Comma-separated backends; the first is the baseline the others are compared with "
                  "(bvh8, bvh, embree, embree-fast, brute, exact, plugin:PATH)")
      ->capture_default_str();
  cmd->add_option("--rays", opt->rays, "Rays per kind")->capture_default_str();
  cmd->add_option("--kinds", opt->kinds, "Ray kinds: camera, uniform, diffuse, shadow, axis (zero direction components: docs/cli.md)")->capture_default_str();
  cmd->add_option("--seed", opt->seed, "Random seed for ray generation")->capture_default_str();
  cmd->add_option("--json", opt->json, "Write the figures as JSON to this file");
  cmd->add_flag("--no-arbiter", opt->no_arbiter, "Do not rule disagreements against the exact backend");
  cmd->add_flag("--strict", opt->strict,
                "Also fail (exit 1) when the arbiter rules any backend's answer wrong, edge cases included");
  cmd->add_option("--arbiter-max-rays", opt->arbiter_max_rays,
                  "Rule at most this many disputed rays per kind (the first ones); 0 rules none")
      ->capture_default_str();
  cmd->callback([opt, &run] { run = [opt] { return run_crosscheck_command(*opt); }; });
}

}  // namespace twinray::cli
