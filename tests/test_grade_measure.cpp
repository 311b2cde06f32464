// The measuring checks of `twinray grade` (twelfth round, docs/grading.md): `performance` times a plugin's batch
// functions beside its single-ray ones and any hit beside closest hit, per ray kind; `complexity` tells a tree
// from a list by how time per ray grows with the primitive count; both also in CPU time (thirteenth round).
// Graded with tests/suites/grading.

#include "harness/grade/grade_run.h"
#include "harness/grade/reports.h"
#include "tests/grade_test_util.h"

#include <gtest/gtest.h>

namespace twinray::grade {
namespace {

using testing::check_named;
using testing::bvh4_plugin;
using testing::scotty_plugin;
using testing::test_plugin;

TEST(GradeMeasure, PerformanceTimesTheBatchPathOnlyWhenThePluginHasOne) {
  const Scorecard with = testing::grade_with_test_suite(bvh4_plugin(), {"performance-soup"});
  const nlohmann::json& f = check_named(with, "performance-soup").figures;
  EXPECT_EQ(f["judged_path"], "batch");
  EXPECT_GT(f["rays_per_second"]["plugin_batch"].get<double>(), 0.0) << f.dump();
  EXPECT_GT(f["speed_vs_bvh_batch"].get<double>(), 0.0);
  EXPECT_GT(f["any_hit"]["rays_per_second"]["plugin"].get<double>(), 0.0);
  EXPECT_GT(f["per_kind"]["camera"]["any"]["bvh"].get<double>(), 0.0);
  EXPECT_TRUE(with.performance.contains("performance-soup"));
  // CPU time (thirteenth round): the worker's clock and the references' thread clock were read, and judge.
  EXPECT_EQ(f["judged_time"], "cpu") << f.dump();
  EXPECT_GT(f["cpu_rays_per_second"]["plugin"].get<double>(), 0.0) << f.dump();
  EXPECT_GT(f["cpu_rays_per_second"]["plugin_batch"].get<double>(), 0.0);
  EXPECT_GT(f["cpu_rays_per_second"]["bvh"].get<double>(), 0.0);
  EXPECT_GT(f["cpu_speed_vs_bvh_batch"].get<double>(), 0.0);
  EXPECT_GT(f["any_hit"]["cpu_rays_per_second"]["plugin"].get<double>(), 0.0);

  const Scorecard without = testing::grade_with_test_suite(scotty_plugin(), {"performance-soup"});
  const nlohmann::json& g = check_named(without, "performance-soup").figures;
  EXPECT_EQ(g["judged_path"], "single");
  EXPECT_TRUE(g["rays_per_second"]["plugin_batch"].is_null()) << g.dump();
  EXPECT_TRUE(g["speed_vs_bvh_batch"].is_null());
  EXPECT_GT(g["rays_per_second"]["plugin"].get<double>(), 0.0);  // the key's meaning since the first round
}

TEST(GradeMeasure, ComplexityTellsATreeFromBruteForce) {
  const Scorecard tree = testing::grade_with_test_suite(scotty_plugin(), {"complexity-grid"});
  const CheckResult& t = check_named(tree, "complexity-grid");
  EXPECT_EQ(t.outcome, Outcome::Pass) << terminal_check_line(t);
  // Judged in CPU time (thirteenth round); the wall-clock exponent is still reported, not asserted (load moves it).
  EXPECT_EQ(t.figures["judged_on"], "cpu") << t.figures.dump();
  EXPECT_LT(t.figures["closest"]["growth_exponent_cpu"].get<double>(), 0.7) << t.figures.dump();
  EXPECT_TRUE(t.figures["closest"]["growth_exponent"].is_number());
  EXPECT_GT(t.figures["closest"]["cpu_seconds_per_ray"][0].get<double>(), 0.0);
  EXPECT_GT(t.figures["any"]["cpu_seconds_per_ray"][1].get<double>(), 0.0);
  EXPECT_TRUE(tree.performance.contains("complexity-grid"));

  const Scorecard brute = testing::grade_with_test_suite(test_plugin("brute"), {"complexity-grid"});
  const CheckResult& b = check_named(brute, "complexity-grid");
  EXPECT_EQ(b.outcome, Outcome::Fail) << terminal_check_line(b);
  EXPECT_GT(b.figures["closest"]["growth_exponent"].get<double>(), 0.7) << terminal_check_line(b);
  EXPECT_GT(b.figures["closest"]["growth_exponent_cpu"].get<double>(), 0.7) << terminal_check_line(b);
  EXPECT_GT(b.figures["closest"]["growth_exponent_cpu"].get<double>(),
            t.figures["closest"]["growth_exponent_cpu"].get<double>());
  EXPECT_NE(b.detail.find("brute force or a tree degenerated"), std::string::npos) << b.detail;
  EXPECT_FALSE(b.reproduce.empty());
  EXPECT_TRUE(brute.passed());  // not required, worth 0 in the test suite
}

}  // namespace
}  // namespace twinray::grade
