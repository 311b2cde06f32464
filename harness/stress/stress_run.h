#pragma once
// A run of the stress catalogue: every selected case on every backend, one outcome each, and a verdict.
// `twinray stress` parses flags into StressRunSettings and writes the JSON this returns (docs/cli.md).

#include "harness/stress/stress_case.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace twinray::stress {

struct StressRunSettings {
  std::vector<std::string> backends;
  std::vector<const StressCase*> cases;  // empty: the whole catalogue
  StressOptions options;
};

struct StressRunReport {
  std::size_t passed = 0, failed = 0, failed_not_required = 0, skipped = 0;
  double seconds = 0.0;
  nlohmann::json json;  // the document of docs/cli.md
  bool ok() const { return failed == 0; }
};

// `print_line` receives each result line (and note lines) as soon as the case has run, then the verdict line.
StressRunReport run_stress(const StressRunSettings& settings, const std::function<void(const std::string&)>& print_line);

}  // namespace twinray::stress
