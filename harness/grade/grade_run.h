#pragma once
// `twinray grade`: every check of a suite on one plugin, in manifest order, each in a fresh plugin worker
// with its own wall-clock and memory limits, into a Scorecard. cli/cmd_grade.cpp only parses flags into
// GradeSettings and writes the outputs.
//
// Rules (docs/grading.md): a check that passes earns its points; a check whose prerequisite ("needs") did
// not pass is skipped and earns none; a check on a scene that needs the shared data folder is skipped and
// worth nothing when the folder is absent; an "if-claimed" check of a property the plugin does not claim
// runs, is reported, and is worth nothing; a measuring check without thresholds is worth nothing. A plugin
// crash or timeout is the outcome of the check it happened in, and the next check starts a new worker. A build
// that timed out or crashed is not repeated by later checks that would give it no more (failed_builds.h), and
// once the run's time budget is spent the checks still to run are reported `timeout` without running.

#include "harness/grade/scorecard.h"

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace twinray::grade {

struct GradeSettings {
  std::filesystem::path plugin;
  std::string suite = "default";          // a bundled suite's name or a folder
  std::vector<std::string> only;           // run just these checks (their prerequisites are then not required)
  std::filesystem::path image_dir;         // disagreement PNGs go here (Scorecard::images; empty: none made)
  std::string twinray = "twinray";         // the program name reproduce lines start with
  // Seconds for the whole run (--time-budget), overriding the suite's "time_budget"; 0: no budget.
  std::optional<double> time_budget;
  // Multiplies every check's time_limit and ray_time_limit and the suite's time_budget (--time-scale): for a
  // grading machine slower or busier than the one the suite was written on. An explicit --time-budget is
  // taken as given. Reproduce lines carry it, so that a replay runs under the same limits.
  double time_scale = 1.0;
  // --time-scale auto: the calibration time_scale was set from (time_calibration.h), recorded in the scorecard.
  std::optional<TimeCalibration> time_calibration;
  // Called once the suite and plugin are loaded, before the first check (the terminal header), then after
  // every check, in order (the terminal report streams its lines from here).
  std::function<void(const Scorecard& card, std::size_t total)> on_start;
  std::function<void(const CheckResult& result, std::size_t done, std::size_t total)> on_check;
};

// Throws InputError for a bad suite, scene or plugin, std::invalid_argument for an unknown --check name.
Scorecard run_grade(const GradeSettings& settings);

}  // namespace twinray::grade
