// --json FILE: the scorecard as JSON (keys in docs/grading.md; the first seven are issue 10's contract).

#include "harness/grade/reports.h"

namespace twinray::grade {

std::string json_file_text(const nlohmann::json& j) {
  // Replace rather than throw on invalid UTF-8: a plugin's name or output may contain anything.
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

nlohmann::json scorecard_json(const Scorecard& card) {
  nlohmann::json checks = nlohmann::json::array();
  for (const CheckResult& c : card.checks) {
    nlohmann::json j = {{"name", c.name},
                        {"category", to_string(c.category)},
                        {"outcome", to_string(c.outcome)},
                        {"points", c.points},
                        {"max_points", c.max_points},
                        {"detail", c.detail},
                        {"reproduce", c.reproduce.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.reproduce)},
                        {"required", c.required},
                        {"visibility", to_string(c.visibility)},
                        {"description", c.description},
                        {"seconds", c.seconds},
                        {"figures", c.figures},
                        {"image", c.image.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.image)}};
    checks.push_back(std::move(j));
  }
  return {{"score", card.score()},
          {"max_score", card.max_score()},
          {"passed", card.passed()},
          {"plugin", card.plugin},
          {"suite", card.suite},
          {"checks", std::move(checks)},
          {"performance", card.performance},
          {"plugin_name", card.plugin_name},
          {"claims", {{"watertight", card.claims.watertight},
                      {"honours_ties", card.claims.honours_ties},
                      {"counts_traversal", card.claims.counts_traversal}}},
          {"batch_functions", {{"intersect_batch", card.intersect_batch}, {"occluded_batch", card.occluded_batch}}},
          {"suite_path", card.suite_path},
          {"counts", {{"pass", card.count(Outcome::Pass)},
                      {"fail", card.count(Outcome::Fail)},
                      {"crash", card.count(Outcome::Crash)},
                      {"timeout", card.count(Outcome::Timeout)},
                      {"skipped", card.count(Outcome::Skipped)}}},
          {"seconds", card.seconds},
          {"time_budget", card.time_budget ? nlohmann::json(*card.time_budget) : nlohmann::json(nullptr)},
          {"time_scale", card.time_scale},
          {"time_scale_auto", card.time_calibration
                                  ? nlohmann::json{{"reference_seconds", card.time_calibration->reference_seconds},
                                                   {"measured_seconds", card.time_calibration->measured_seconds},
                                                   {"scale", card.time_calibration->scale}}
                                  : nlohmann::json(nullptr)}};
}

}  // namespace twinray::grade
