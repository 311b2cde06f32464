// The plugin's optional batch functions (intersect_batch, occluded_batch) through the isolated worker and in
// `twinray grade`'s batch-calls check: the worker calls them when asked (BatchPath::PluginBatch, the default, as
// the in-process backend does), reports a crash or hang in them like one in a single-ray call, and the grader
// judges their answers (docs/grading.md, "batch-calls"); a plugin without them is not graded on them.

#include "backends/plugin/isolated_plugin_backend.h"
#include "backends/plugin/plugin_backend.h"
#include "core/geometry/hit.h"
#include "core/scene/procedural.h"
#include "core/sampling/rng.h"
#include "harness/grade/grade_run.h"
#include "harness/grade/reports.h"
#include "tests/grade_test_util.h"
#include "tests/plugin_failure_test_util.h"
#include "tests/ray_test_util.h"

#include <gtest/gtest.h>

#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace twinray::grade {
namespace batch_test {  // named: the unity build puts several test files into one translation unit

using testing::bvh4_plugin;
using testing::check_lines;
using testing::check_named;
using test::failure_of;

PluginLimits short_limits() {
  PluginLimits limits;
  limits.query_seconds = 0.3;
  limits.build_seconds = 30.0;
  return limits;
}

// A 16x16 grid of unit squares in z = 0 (core's grid_mesh, which leaves readable bytes past the last vertex as
// the ABI promises) and rays at it from above and beside it: hits and misses.
SceneGeometry grid_scene() { return grid_mesh(16, 16); }

std::vector<Ray> grid_rays(std::size_t count) {
  Rng rng(7, 3);
  std::vector<Ray> rays;
  for (std::size_t i = 0; i < count; ++i) {
    const glm::vec3 org{rng.next_float() * 24.0f - 4.0f, rng.next_float() * 24.0f - 4.0f, 1.0f + rng.next_float() * 4.0f};
    const glm::vec3 dir{rng.next_float() - 0.5f, rng.next_float() - 0.5f, -1.0f};
    // Every third ray may end before the grid.
    rays.push_back(test::make_ray(org, dir, 0.0f, i % 3 == 0 ? 2.5f : std::numeric_limits<float>::infinity()));
  }
  return rays;
}

// The worker's batch path gives the in-process backend's answers to the bit (same functions, same call sizes),
// and the single-call path the single-ray functions' answers.
TEST(BatchCalls, IsolatedBatchPathMatchesTheInProcessBackendToTheBit) {
  const SceneGeometry g = grid_scene();
  const std::vector<Ray> rays = grid_rays(5000);  // more than one worker request (4096 rays)
  const std::unique_ptr<Backend> local = load_plugin_backend(bvh4_plugin());
  local->build(g);
  const auto isolated = make_isolated_plugin_backend(bvh4_plugin(), short_limits());
  EXPECT_TRUE(isolated->has_intersect_batch());
  EXPECT_TRUE(isolated->has_occluded_batch());
  EXPECT_EQ(isolated->batch_path(), BatchPath::PluginBatch);
  isolated->build(g);
  std::vector<Hit> want(rays.size()), got(rays.size());
  std::vector<std::uint8_t> want_occluded(rays.size()), got_occluded(rays.size());
  local->intersect(rays, want);
  local->occluded(rays, want_occluded);
  isolated->intersect(rays, got);
  isolated->occluded(rays, got_occluded);
  std::size_t hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(got[i].geom_id, want[i].geom_id) << i;
    ASSERT_EQ(got[i].prim_id, want[i].prim_id) << i;
    ASSERT_EQ(got[i].t, want[i].t) << i;
    ASSERT_EQ(got_occluded[i], want_occluded[i]) << i;
    hits += got[i].geom_id != kInvalidId ? 1 : 0;
  }
  EXPECT_GT(hits, rays.size() / 4);  // hits and misses both
  EXPECT_LT(hits, rays.size());
}

// Bug 4 of bvh4 (the batch path carries the previous ray's t over as the next ray's bound): in process its
// batch answers are wrong, through the worker's batch path too, while its single-call path is right.
TEST(BatchCalls, BatchOnlyBugShowsOnlyOnTheBatchPath) {
  const SceneGeometry g = grid_scene();
  const std::vector<Ray> rays = grid_rays(600);
  const auto reference = make_isolated_plugin_backend(bvh4_plugin(), short_limits());
  reference->build(g);
  std::vector<Hit> right(rays.size());
  reference->intersect(rays, right);
  const auto wrong_answers = [&](BatchPath path) {
    const auto plugin = make_isolated_plugin_backend(bvh4_plugin("batch_stale_tmax"), short_limits());
    plugin->set_batch_path(path);
    plugin->build(g);
    std::vector<Hit> hits(rays.size());
    plugin->intersect(rays, hits);
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) wrong += hits[i].geom_id != right[i].geom_id || hits[i].t != right[i].t;
    return wrong;
  };
  EXPECT_GT(wrong_answers(BatchPath::PluginBatch), 0u);
  EXPECT_EQ(wrong_answers(BatchPath::SingleCalls), 0u);
}

// A crash or hang in a batch function ends the worker like one in intersect1: stage intersect_batch /
// occluded_batch, the call's first ray, the cause. The hostile batch functions fail on the third ray of any
// call of three or more rays; its single-ray functions answer everything.
TEST(BatchCalls, CrashOrHangInABatchFunctionIsReportedWithItsStageAndCall) {
  const SceneGeometry g = grid_scene();
  const std::vector<Ray> rays = grid_rays(600);
  {
    const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_BATCH_SEGV_PLUGIN, short_limits());
    plugin->build(g);
    std::vector<Hit> hits(rays.size());
    std::vector<Hit> two(2);
    plugin->intersect(std::span<const Ray>(rays.data(), 2), two);  // a call of 2 rays: no trigger
    const std::optional<PluginFailure> f = failure_of([&] { plugin->intersect(rays, hits); });
    ASSERT_TRUE(f.has_value());
    EXPECT_EQ(f->kind, PluginFailureKind::Crash);
    EXPECT_EQ(f->cause, "signal");
    EXPECT_EQ(f->signal_name, "SIGSEGV");
    EXPECT_EQ(f->stage, "intersect_batch");
    ASSERT_TRUE(f->ray_index.has_value());
    EXPECT_EQ(*f->ray_index, 0u);  // the first ray of the failing call (0..255)
    EXPECT_NE(std::string(f->what()).find("a call of 256 rays from ray 0"), std::string::npos) << f->what();
  }
  {
    const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_BATCH_LOOP_PLUGIN, short_limits());
    plugin->build(g);
    std::vector<std::uint8_t> occluded(rays.size());
    const std::optional<PluginFailure> f = failure_of([&] { plugin->occluded(rays, occluded); });
    ASSERT_TRUE(f.has_value());
    EXPECT_EQ(f->kind, PluginFailureKind::Timeout);
    EXPECT_EQ(f->stage, "occluded_batch");
  }
  {
    // The same plugin on the single-call path: every ray answered.
    const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_BATCH_SEGV_PLUGIN, short_limits());
    plugin->set_batch_path(BatchPath::SingleCalls);
    plugin->build(g);
    std::vector<Hit> hits(rays.size());
    EXPECT_NO_THROW(plugin->intersect(rays, hits));
  }
}

// A plugin without batch functions: not applicable, skipped, worth nothing, and the run still passes.
TEST(GradeBatchCalls, PluginWithoutBatchFunctionsIsNotGradedOnThem) {
  const Scorecard card = testing::grade_with_test_suite(testing::scotty_plugin(), {"batch-calls-cornell"});
  const CheckResult& c = check_named(card, "batch-calls-cornell");
  EXPECT_EQ(c.outcome, Outcome::Skipped) << terminal_check_line(c);
  EXPECT_EQ(c.max_points, 0.0);
  EXPECT_NE(c.detail.find("not applicable"), std::string::npos) << c.detail;
  EXPECT_EQ(c.figures.at("applicable"), false);
  EXPECT_TRUE(card.passed());
  EXPECT_FALSE(card.intersect_batch || card.occluded_batch);
  const nlohmann::json j = scorecard_json(card);
  EXPECT_EQ(j.at("batch_functions").at("intersect_batch"), false);
}

// A plugin with only intersect_batch (the brute-force example): that one is judged, occluded goes through
// occluded1, and a correct plugin passes.
TEST(GradeBatchCalls, PluginWithOneBatchFunctionHasThatOneJudged) {
  const Scorecard card = testing::grade_with_test_suite(TWINRAY_TEST_BRUTE_PLUGIN, {"batch-calls-cornell"});
  const CheckResult& c = check_named(card, "batch-calls-cornell");
  EXPECT_EQ(c.outcome, Outcome::Pass) << terminal_check_line(c);
  EXPECT_GT(c.max_points, 0.0);
  EXPECT_NE(c.detail.find("through intersect_batch right"), std::string::npos) << c.detail;
  EXPECT_TRUE(card.intersect_batch);
  EXPECT_FALSE(card.occluded_batch);
}

// A crash in a batch function fails the check as a crash, reproduced by rerunning the check.
TEST(GradeBatchCalls, CrashInABatchFunctionIsTheChecksCrash) {
  const Scorecard card = testing::grade_with_test_suite(TWINRAY_TEST_HOSTILE_BATCH_SEGV_PLUGIN, {"batch-calls-cornell"});
  const CheckResult& c = check_named(card, "batch-calls-cornell");
  EXPECT_EQ(c.outcome, Outcome::Crash) << terminal_check_line(c);
  EXPECT_NE(c.detail.find("intersect_batch"), std::string::npos) << c.detail;
  EXPECT_NE(c.reproduce.find("--check batch-calls-cornell"), std::string::npos) << c.reproduce;
  EXPECT_FALSE(card.passed());
}

}  // namespace batch_test
}  // namespace twinray::grade
