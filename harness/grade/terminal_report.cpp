// The terminal scorecard: what a student reads after `twinray grade`.

#include "harness/grade/reports.h"

#include <fmt/core.h>

#include <cmath>

namespace twinray::grade {

std::string format_points(double points) {
  if (points == std::floor(points) && std::fabs(points) < 1e15) return fmt::format("{}", static_cast<long long>(points));
  return fmt::format("{:.6g}", points);
}

namespace {

std::string claims_text(const BackendTraits& t) {
  const auto yes_no = [](bool b, const char* what) { return fmt::format("{}{}", b ? "" : "not ", what); };
  return fmt::format("{}, {}, {}", yes_no(t.watertight, "watertight"), yes_no(t.honours_ties, "honours ties"),
                     yes_no(t.counts_traversal, "counts traversal"));
}

std::string outcome_label(const CheckResult& c) {
  // Upper case for what fails the run, so it stands out in a long list.
  std::string s(to_string(c.outcome));
  if (c.fails_run())
    for (char& ch : s) ch = static_cast<char>(ch - 'a' + 'A');
  return s;
}

}  // namespace

std::string terminal_header(const Scorecard& card, std::size_t checks) {
  std::string budget = card.time_budget ? fmt::format(", time budget {:g} s", *card.time_budget) : "";
  if (card.time_scale != 1.0) budget += fmt::format(", time limits x {:g}", card.time_scale);
  if (card.time_calibration)
    budget += fmt::format("{} (--time-scale auto: the reference workload took {:.3f} s here, {:.3f} s on the reference "
                          "machine)", card.time_scale == 1.0 ? ", time limits x 1" : "",
                          card.time_calibration->measured_seconds, card.time_calibration->reference_seconds);
  const std::string batch = card.intersect_batch && card.occluded_batch ? "intersect_batch, occluded_batch"
                            : card.intersect_batch                       ? "intersect_batch"
                            : card.occluded_batch                        ? "occluded_batch"
                                                                         : "none";
  return fmt::format("twinray grade: {} ({})\n  suite {} ({} checks, {}{})\n  the plugin claims: {}\n  batch functions: {}\n\n",
                     card.plugin_name, card.plugin, card.suite, checks, card.suite_path, budget, claims_text(card.claims),
                     batch);
}

std::string terminal_check_line(const CheckResult& c) {
  std::string line = fmt::format("{:<8} {:>6}  {:<13} {:<30} {}\n", outcome_label(c),
                                 format_points(c.points) + "/" + format_points(c.max_points), to_string(c.category),
                                 c.name, c.detail);
  if (!c.reproduce.empty()) line += fmt::format("{:<8} reproduce: {}\n", "", c.reproduce);
  if (!c.image.empty()) line += fmt::format("{:<8} image: {}\n", "", c.image);
  return line;
}

std::string terminal_totals(const Scorecard& card) {
  std::size_t required_failed = 0;
  for (const CheckResult& c : card.checks) required_failed += c.fails_run() ? 1 : 0;
  const double max = card.max_score();
  std::string s = fmt::format("\nscore {} / {}{}: {} passed, {} failed, {} crashed, {} timed out, {} skipped, in {:.1f} s\n",
                              format_points(card.score()), format_points(max),
                              max > 0.0 ? fmt::format(" ({:.1f}%)", 100.0 * card.score() / max) : "",
                              card.count(Outcome::Pass), card.count(Outcome::Fail), card.count(Outcome::Crash),
                              card.count(Outcome::Timeout), card.count(Outcome::Skipped), card.seconds);
  s += card.passed() ? std::string("verdict: PASS (every required check passed)\n")
                     : fmt::format("verdict: FAIL ({} required check{} failed)\n", required_failed,
                                   required_failed == 1 ? "" : "s");
  return s;
}

}  // namespace twinray::grade
