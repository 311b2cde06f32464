// twinray stress: the catalogue of cases where floating point gets hard (cli/stress, docs/stress.md),
// each run on every backend asked for, one pass/fail line per case and backend.

#include "backends/registry.h"
#include "cli/commands.h"
#include "cli/stress/stress_case.h"
#include "core/util/atomic_file.h"
#include "core/util/fp_mode.h"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace twinray::cli {

namespace {

struct StressCommandOptions {
  std::string backends = "bvh,brute,embree,embree-fast";
  std::vector<std::string> cases;
  std::string json;
  double effort = 1.0;
  bool list = false;
};

int run_stress(const StressCommandOptions& opt) {
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
  if (selected.empty())
    for (const StressCase& c : all_cases()) selected.push_back(&c);

  const ScopedFlushDenormals ftz;  // the mode every backend and the renderer run in
  const StressOptions options{opt.effort};
  std::size_t failed = 0, failed_not_required = 0, passed = 0, skipped = 0;
  nlohmann::json j_cases = nlohmann::json::array();
  const auto start = std::chrono::steady_clock::now();
  for (const StressCase* c : selected) {
    for (const std::string& backend : backends) {
      const auto case_start = std::chrono::steady_clock::now();
      Outcome outcome;
      try {
        outcome = c->run(backend, options);
      } catch (const std::exception& e) {
        outcome.status = Status::Fail;
        outcome.figures = fmt::format("exception: {}", e.what());
      }
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - case_start).count();
      const bool failure = outcome.counts_as_failure();
      if (outcome.status == Status::Pass) ++passed;
      else if (outcome.status == Status::Skip) ++skipped;
      else if (failure) ++failed;
      else ++failed_not_required;
      const std::string status =
          outcome.status == Status::Fail && !outcome.required ? "fail*" : std::string(to_string(outcome.status));
      fmt::print("{:<5} {:<26} {:<12} {:6.2f} s  {}\n", status, c->name, backend, seconds, outcome.figures);
      if (!outcome.note.empty() && outcome.status != Status::Pass) fmt::print("      note: {}\n", outcome.note);
      std::fflush(stdout);
      j_cases.push_back({{"case", c->name},
                         {"family", c->family},
                         {"backend", backend},
                         {"status", std::string(to_string(outcome.status)) == "FAIL" ? "fail" : to_string(outcome.status)},
                         {"required", outcome.required},
                         {"seconds", seconds},
                         {"figures", outcome.figures},
                         {"note", outcome.note},
                         {"details", outcome.json}});
    }
  }
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  fmt::print("verdict: {} ({} passed, {} failed, {} failed but not required (fail*), {} skipped) in {:.1f} s\n",
             failed == 0 ? "PASS" : "FAIL", passed, failed, failed_not_required, skipped, total);
  if (!opt.json.empty()) {
    const nlohmann::json j = {{"backends", backends},
                              {"effort", opt.effort},
                              {"results", j_cases},
                              {"passed", passed},
                              {"failed", failed},
                              {"failed_not_required", failed_not_required},
                              {"skipped", skipped},
                              {"seconds", total},
                              {"verdict", failed == 0 ? "pass" : "fail"}};
    write_file_atomically(opt.json, j.dump(2) + "\n");
  }
  return failed == 0 ? kExitOk : kExitCheckFailed;
}

}  // namespace

void add_stress_command(CLI::App& app, CommandRunner& run) {
  auto opt = std::make_shared<StressCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "stress",
      "Run the catalogue of numerically hard cases (docs/stress.md) on several backends.\n"
      "Exit code: 0 every required case passed, 1 a required case failed, 2 bad input.");
  cmd->add_option("--backends", opt->backends, "Comma-separated backends (bvh, embree, embree-fast, brute, plugin:PATH)")
      ->capture_default_str();
  cmd->add_option("--case", opt->cases, "Run only this case (repeatable); see --list");
  cmd->add_option("--json", opt->json, "Write every outcome with its figures as JSON to this file");
  cmd->add_option("--effort", opt->effort, "Scale ray and sample counts (1 = default, about a minute in all)")
      ->capture_default_str();
  cmd->add_flag("--list", opt->list, "List the cases and exit");
  cmd->callback([opt, &run] { run = [opt] { return run_stress(*opt); }; });
}

}  // namespace twinray::cli
