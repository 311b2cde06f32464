// twinray trace: one ray, replayed bit for bit, through several backends side by side.

#include "backends/registry.h"
#include "cli/commands.h"
#include "core/util/atomic_file.h"
#include "core/geometry/ray_text.h"
#include "harness/trace/trace_run.h"

#include <fmt/core.h>

#include <memory>
#include <stdexcept>

namespace twinray::cli {

namespace {

struct TraceOptions {
  std::string scene;
  std::string backends = "bvh,embree";
  std::string ray;
  std::string json;
  bool no_visits = false;
};

int run_trace_command(const TraceOptions& opt) {
  trace::TraceSettings settings;
  settings.scene = opt.scene;
  settings.visits = !opt.no_visits;
  try {
    settings.backends = parse_backend_list(opt.backends);
    settings.ray = parse_ray(opt.ray);
  } catch (const std::invalid_argument& e) {
    return report_bad_input("trace", e.what());
  }
  const trace::TraceReport report = trace::run_trace(settings);
  fmt::print("{}", report.text);
  if (!opt.json.empty()) write_file_atomically(opt.json, report.json.dump(2) + "\n");
  return report.all_answered ? kExitOk : kExitCheckFailed;
}

}  // namespace

void add_trace_command(CLI::App& app, CommandRunner& run) {
  auto opt = std::make_shared<TraceOptions>();
  CLI::App* cmd = app.add_subcommand(
      "trace",
      "Trace one ray through several backends and print every answer side by side (closest hit: t in decimal\n"
      "and hexadecimal, u, v, ids, normal; any-hit), the work of counting backends and bvh's visit order.\n"
      "Exit code: 0 every backend answered, 1 a backend failed (a plugin crashed or timed out), 2 bad input.");
  cmd->add_option("scene", opt->scene,
                  "Scene: a .json scene, a bare .obj/.ply mesh, $TWINRAY_SHARED/... or procedural:KIND[:ARG]... "
                  "(docs/grading.md lists the kinds)")
      ->required();
  cmd->add_option("--backends", opt->backends,
                  "Comma-separated backends, compared with the first (bvh8, bvh, embree, embree-fast, brute, plugin:PATH, plugin-inprocess:PATH)")
      ->capture_default_str();
  cmd->add_option("--ray", opt->ray,
                  "'ox oy oz dx dy dz tmin tmax': decimal or hexadecimal floats (0x1.8p+0), inf allowed")
      ->required();
  cmd->add_flag("--no-visits", opt->no_visits, "Leave out bvh's list of nodes entered");
  cmd->add_option("--json", opt->json, "Write the answers as JSON to this file");
  cmd->callback([opt, &run] { run = [opt] { return run_trace_command(*opt); }; });
}

}  // namespace twinray::cli
