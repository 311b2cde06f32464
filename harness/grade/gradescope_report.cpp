// --gradescope FILE: Gradescope's autograder results.json ("Autograder Specifications", output format):
// top-level score, execution_time, output, stdout_visibility, extra_data and tests; per test score,
// max_score, status, name, output, tags, visibility and extra_data. Only documented keys are written.

#include "harness/grade/reports.h"

#include <fmt/core.h>

#include <cmath>

namespace twinray::grade {

nlohmann::json gradescope_json(const Scorecard& card) {
  nlohmann::json tests = nlohmann::json::array();
  for (const CheckResult& c : card.checks) {
    std::string output = fmt::format("{}: {}", to_string(c.outcome), c.detail);
    if (!c.reproduce.empty()) output += "\n\nReproduce it with:\n" + c.reproduce;
    if (c.figures.contains("plugin_output"))
      output += "\n\nWhat the plugin printed:\n" + c.figures["plugin_output"].get<std::string>();
    if (!c.description.empty()) output = c.description + "\n\n" + output;
    nlohmann::json t = {{"name", fmt::format("{} ({})", c.name, to_string(c.category))},
                        {"score", c.points},
                        {"max_score", c.max_points},
                        {"output", output},
                        {"tags", {to_string(c.category), to_string(c.outcome)}},
                        {"visibility", to_string(c.visibility)},
                        {"extra_data", {{"check", c.name},
                                        {"category", to_string(c.category)},
                                        {"outcome", to_string(c.outcome)},
                                        {"required", c.required},
                                        {"seconds", c.seconds}}}};
    // Gradescope derives pass/fail from score against max_score; say it outright so a check worth no
    // points still shows its result. A skipped check keeps the derived status (its output says why).
    if (c.outcome == Outcome::Pass) t["status"] = "passed";
    else if (c.failed()) t["status"] = "failed";
    tests.push_back(std::move(t));
  }
  const std::string summary =
      fmt::format("twinray grade, suite '{}': {} of {} checks passed ({} failed, {} crashed, {} timed out, {} skipped).\n"
                  "Each test below says what was checked, what went wrong and the command that reproduces it.",
                  card.suite, card.count(Outcome::Pass), card.checks.size(), card.count(Outcome::Fail),
                  card.count(Outcome::Crash), card.count(Outcome::Timeout), card.count(Outcome::Skipped));
  return {{"score", card.score()},
          {"execution_time", static_cast<long long>(std::ceil(card.seconds))},
          {"output", summary},
          {"test_output_format", "text"},
          // twinray's own stdout lists every check, hidden ones included: instructors only.
          {"stdout_visibility", "hidden"},
          {"extra_data", {{"plugin", card.plugin_name}, {"suite", card.suite}, {"passed", card.passed()}}},
          {"tests", std::move(tests)}};
}

}  // namespace twinray::grade
