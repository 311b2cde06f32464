// twinray stress: the catalogue of cases where floating point gets hard (harness/stress, docs/stress.md),
// each run on every backend asked for, one pass/fail line per case and backend.

#include "backends/registry.h"
#include "cli/commands.h"
#include "harness/stress/stress_run.h"
#include "core/util/atomic_file.h"

#include <fmt/core.h>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace twinray::cli {

namespace {

struct StressCommandOptions {
  std::string backends = "bvh8,bvh,brute,exact,embree,embree-fast";
  std::vector<std::string> cases;
  std::string json;
  double effort = 1.0;
  bool list = false;
};

int run_stress_command(const StressCommandOptions& opt) {
  using namespace twinray::stress;
  if (opt.list) {
    for (const StressCase& c : all_cases()) fmt::print("{:<26} {:<16} {}\n", c.name, c.family, c.summary);
    return kExitOk;
  }
  std::vector<std::string> backends;
  try {
    backends = parse_backend_list(opt.backends);
  } catch (const std::invalid_argument& e) {
    return report_bad_input("stress", e.what());
  }
  if (!(opt.effort > 0.0 && opt.effort <= 100.0)) {
    return report_bad_input("stress", fmt::format("--effort must be in (0, 100], got {}", opt.effort));
  }
  std::vector<const StressCase*> selected;
  for (const std::string& name : opt.cases) {
    const StressCase* c = find_case(name);
    if (!c) {
      std::string known;
      for (const StressCase& k : all_cases()) known += (known.empty() ? "" : ", ") + k.name;
      return report_bad_input("stress", fmt::format("unknown case '{}' (known: {})", name, known));
    }
    selected.push_back(c);
  }
  StressRunSettings settings;
  settings.backends = std::move(backends);
  settings.cases = std::move(selected);
  settings.options = StressOptions{opt.effort};
  const StressRunReport report = run_stress(settings, [](const std::string& line) {
    fmt::print("{}\n", line);
    std::fflush(stdout);
  });
  if (!opt.json.empty()) write_file_atomically(opt.json, report.json.dump(2) + "\n");
  return report.ok() ? kExitOk : kExitCheckFailed;
}

}  // namespace

void add_stress_command(CLI::App& app, CommandRunner& run) {
  auto opt = std::make_shared<StressCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "stress",
      "Run the catalogue of numerically hard cases (docs/stress.md) on several backends.\n"
      "Exit code: 0 every required case passed, 1 a required case failed, 2 bad input.");
  cmd->add_option("--backends", opt->backends, "Comma-separated backends (bvh8, bvh, embree, embree-fast, brute, exact, plugin:PATH)")
      ->capture_default_str();
  cmd->add_option("--case", opt->cases, "Run only this case (repeatable); see --list");
  cmd->add_option("--json", opt->json, "Write every outcome with its figures as JSON to this file");
  cmd->add_option("--effort", opt->effort, "Scale ray and sample counts (1 = default, about a minute in all)")
      ->capture_default_str();
  cmd->add_flag("--list", opt->list, "List the cases and exit");
  cmd->callback([opt, &run] { run = [opt] { return run_stress_command(*opt); }; });
}

}  // namespace twinray::cli
