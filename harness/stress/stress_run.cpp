#include "harness/stress/stress_run.h"

#include "core/util/fp_mode.h"

#include <fmt/core.h>

#include <chrono>
#include <exception>

namespace twinray::stress {

StressRunReport run_stress(const StressRunSettings& settings, const std::function<void(const std::string&)>& print_line) {
  std::vector<const StressCase*> selected = settings.cases;
  if (selected.empty())
    for (const StressCase& c : all_cases()) selected.push_back(&c);

  const ScopedFlushDenormals ftz;  // the mode every backend and the renderer run in
  StressRunReport report;
  nlohmann::json j_cases = nlohmann::json::array();
  const auto start = std::chrono::steady_clock::now();
  for (const StressCase* c : selected) {
    for (const std::string& backend : settings.backends) {
      const auto case_start = std::chrono::steady_clock::now();
      Outcome outcome;
      try {
        outcome = c->run(backend, settings.options);
      } catch (const std::exception& e) {
        outcome.status = Status::Fail;
        outcome.figures = fmt::format("exception: {}", e.what());
      }
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - case_start).count();
      if (outcome.status == Status::Pass) ++report.passed;
      else if (outcome.status == Status::Skip) ++report.skipped;
      else if (outcome.counts_as_failure()) ++report.failed;
      else ++report.failed_not_required;
      const std::string status =
          outcome.status == Status::Fail && !outcome.required ? "fail*" : std::string(to_string(outcome.status));
      print_line(fmt::format("{:<5} {:<26} {:<12} {:6.2f} s  {}", status, c->name, backend, seconds, outcome.figures));
      if (!outcome.note.empty() && outcome.status != Status::Pass) print_line(fmt::format("      note: {}", outcome.note));
      j_cases.push_back({{"case", c->name},
                         {"family", c->family},
                         {"backend", backend},
                         {"status", outcome.status == Status::Fail ? std::string("fail") : std::string(to_string(outcome.status))},
                         {"required", outcome.required},
                         {"seconds", seconds},
                         {"figures", outcome.figures},
                         {"note", outcome.note},
                         {"details", outcome.json}});
    }
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  print_line(fmt::format("verdict: {} ({} passed, {} failed, {} failed but not required (fail*), {} skipped) in {:.1f} s",
                         report.ok() ? "PASS" : "FAIL", report.passed, report.failed, report.failed_not_required,
                         report.skipped, report.seconds));
  report.json = {{"backends", settings.backends},
                 {"effort", settings.options.effort},
                 {"results", j_cases},
                 {"passed", report.passed},
                 {"failed", report.failed},
                 {"failed_not_required", report.failed_not_required},
                 {"skipped", report.skipped},
                 {"seconds", report.seconds},
                 {"verdict", report.ok() ? "pass" : "fail"}};
  return report;
}

}  // namespace twinray::stress
