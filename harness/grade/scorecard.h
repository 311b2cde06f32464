#pragma once
// The result of grading one plugin with one suite: every check's outcome, points, one-line detail and
// reproduce command, and the totals. The output modules (terminal_report, json_report, gradescope_report,
// junit_report) each write one format from this and nothing else.

#include "core/backend/backend.h"
#include "core/image/image.h"
#include "harness/grade/time_calibration.h"
#include "harness/grade/vocabulary.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace twinray::grade {

struct CheckResult {
  std::string name;
  Category category = Category::Build;
  Outcome outcome = Outcome::Skipped;
  double points = 0.0;
  double max_points = 0.0;
  bool required = true;  // a fail, crash or timeout of a required check fails the run (exit code 1)
  Visibility visibility = Visibility::Visible;
  std::string description;  // from the suite
  std::string detail;       // one line: what happened, with the key figure
  std::string reproduce;    // one command line that replays the failure (empty when the check passed)
  std::string image;        // path of the disagreement PNG (written with the other outputs), or empty
  double seconds = 0.0;
  // The numbers behind the verdict; for a crash, timeout or contract violation also "plugin_output", what
  // the plugin printed (captured by its worker, truncated).
  nlohmann::json figures = nlohmann::json::object();

  bool failed() const { return outcome == Outcome::Fail || outcome == Outcome::Crash || outcome == Outcome::Timeout; }
  bool fails_run() const { return required && failed(); }
};

// An image to be written with the other outputs once the run is complete (none is left behind by a run that
// ends in bad input).
struct PendingImage {
  std::filesystem::path path;
  Image image;
};

struct Scorecard {
  std::string plugin;         // absolute path of the plugin
  std::string plugin_name;    // "plugin:NAME"
  BackendTraits claims;       // what the plugin's flags claim
  bool intersect_batch = false;  // the plugin has the optional batch entry points (the batch-calls check's
  bool occluded_batch = false;   // applicability)
  std::string suite;          // suite name
  std::string suite_path;     // the suite's manifest
  std::vector<CheckResult> checks;
  nlohmann::json performance = nlohmann::json::object();  // figures of the performance and tree-quality checks
  double seconds = 0.0;
  std::optional<double> time_budget;  // seconds for the whole run (the suite's or --time-budget), if any
  double time_scale = 1.0;            // --time-scale: what every time limit of the suite was multiplied by
  std::optional<TimeCalibration> time_calibration;  // --time-scale auto: the measure time_scale came from
  std::vector<PendingImage> images;

  double score() const;
  double max_score() const;
  bool passed() const;  // every required check passed (or was skipped)
  std::size_t count(Outcome o) const;
};

}  // namespace twinray::grade
