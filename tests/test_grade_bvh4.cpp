// `twinray grade` against a third independent BVH: the 4-wide SIMD BVH of tests/plugins/bvh4_plugin.cpp
// (binned SAH collapsed to 4 wide, SSE slab tests of 4 children at once, Baldwin-Weber float triangles,
// threaded build, batch entry points; claims the tie rule and counts its traversal, not watertightness).
// Fairness: the correct build earns every point of the test suite. Generality: each of its wide-BVH bugs
// loses points in the check expected to catch it, or, where no check can, the test says why.
// docs/grading.md, "A third plugin: a 4-wide SIMD BVH".

#include "harness/grade/grade_run.h"
#include "harness/grade/reports.h"
#include "tests/cli_runner.h"
#include "tests/grade_test_util.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace twinray::grade {
namespace bvh4_test {  // named: the unity build puts several test files into one translation unit

using testing::bvh4_plugin;
using testing::check_lines;
using testing::check_named;
Scorecard grade_bvh4(const std::filesystem::path& plugin, std::vector<std::string> only = {}) {
  return testing::grade_with_test_suite(plugin, std::move(only));
}

TEST(GradeBvh4, CorrectBvh4GetsFullMarks) {
  const Scorecard card = grade_bvh4(bvh4_plugin());
  EXPECT_TRUE(card.passed()) << check_lines(card);
  EXPECT_EQ(card.score(), card.max_score()) << check_lines(card);
  EXPECT_GT(card.max_score(), 0.0);
  for (const CheckResult& c : card.checks) {
    if (c.category == Category::Watertight) {
      // Not claimed: a float Baldwin-Weber test loses rays through shared edges. Reported, worth nothing.
      EXPECT_EQ(c.max_points, 0.0) << terminal_check_line(c);
      EXPECT_FALSE(c.required) << terminal_check_line(c);
      continue;
    }
    if (c.category == Category::Ties) {  // claimed, so required and worth its points
      EXPECT_TRUE(c.required) << terminal_check_line(c);
      EXPECT_GT(c.max_points, 0.0) << terminal_check_line(c);
    }
    EXPECT_EQ(c.outcome, Outcome::Pass) << terminal_check_line(c);
  }
}

using Bvh4Bug = testing::GradeBugCase;

class GradeBvh4Bugs : public ::testing::TestWithParam<Bvh4Bug> {};

TEST_P(GradeBvh4Bugs, LoseThePointsOfTheirCheck) {
  const Bvh4Bug& b = GetParam();
  testing::expect_caught(grade_bvh4(bvh4_plugin(b.bug), {b.caught_by, b.still_passes}), b);
}

INSTANTIATE_TEST_SUITE_P(
    Bvh4Bugs, GradeBvh4Bugs,
    ::testing::Values(
        // Empty slots padded with NaN boxes: the slab drops NaN, so every ray "hits" them and follows the
        // empty reference (a leaf far past the primitives). A scene of at most 4 primitives is one leaf, no node.
        Bvh4Bug{"empty-slot-nan", "closest-cornell", Outcome::Crash, "in intersect", "build-empty"},
        // A node whose 4 children are all hit loses the farthest.
        Bvh4Bug{"sort-drops-4th", "closest-soup", Outcome::Fail, "answers wrong", "build-empty"},
        // The collapse writes a third node's second child over the third slot: a subtree is lost.
        Bvh4Bug{"collapse-3-loses", "closest-cornell", Outcome::Fail, "answers wrong", "build-empty"},
        // Occluded as soon as a leaf's box is entered.
        Bvh4Bug{"anyhit-leaf-box", "any-hit-cornell", Outcome::Fail, "answers wrong", "closest-soup"},
        // Equal t keeps the first copy found: the claimed tie rule is broken.
        Bvh4Bug{"tie-t-only", "ties-duplicates", Outcome::Fail, "answers wrong", "closest-soup"},
        // Pruning against the best t itself: the copy with the lowest prim_id in another flat leaf is skipped.
        Bvh4Bug{"prune-no-slack", "ties-duplicates-box", Outcome::Fail, "answers wrong", "ties-duplicates"},
        // occluded_batch stores a last group of fewer than 4 answers whole: the worker's guard bytes after the
        // answers catch it (every answer is right; the single-ray checks never call it).
        Bvh4Bug{"batch-writes-past", "batch-calls-cornell", Outcome::Fail, "wrote past its answers",
                "closest-soup"}),
    [](const ::testing::TestParamInfo<Bvh4Bug>& param) {
      std::string name = param.param.bug;
      for (char& c : name)
        if (c == '-') c = '_';
      return name;
    });

// Children visited farthest-exit first: every answer right (a closest-hit traversal's order changes only its
// work), and the grader says so; the tree-quality figures show the extra work.
TEST(GradeBvh4, WrongVisitOrderKeepsEveryAnswerRight) {
  const std::vector<std::string> checks = {"closest-soup", "tree-quality-soup"};
  const auto per_ray = [](const Scorecard& card, const char* figure) {
    return check_named(card, "tree-quality-soup").figures.at(figure).at("plugin").get<double>();
  };
  const Scorecard good = grade_bvh4(bvh4_plugin(), checks);
  const Scorecard card = grade_bvh4(bvh4_plugin("sort-by-far"), checks);
  EXPECT_EQ(check_named(card, "closest-soup").outcome, Outcome::Pass) << check_lines(card);
  EXPECT_EQ(check_named(card, "tree-quality-soup").outcome, Outcome::Pass) << check_lines(card);
  EXPECT_GT(per_ray(card, "primitives_per_ray"), per_ray(good, "primitives_per_ray")) << check_lines(card);
}

// Flush-to-zero and denormals-are-zero set in build and left set: no bundled ray reaches a subnormal, so every
// answer is right, but the ABI says a call leaves the floating-point environment as it found it (in process it
// would change the host's arithmetic). The worker compares the control bits around every call.
TEST(GradeBvh4, FloatingPointEnvironmentLeftChangedIsAContractViolation) {
  const Scorecard card = grade_bvh4(bvh4_plugin("ftz-left-set"), {"closest-soup"});
  const CheckResult& caught = check_named(card, "closest-soup");
  EXPECT_EQ(caught.outcome, Outcome::Fail) << check_lines(card);
  EXPECT_EQ(caught.points, 0.0);
  EXPECT_NE(caught.detail.find("left the floating-point environment changed in build"), std::string::npos)
      << caught.detail;
  EXPECT_NE(caught.detail.find("flush-to-zero set, denormals-are-zero set"), std::string::npos) << caught.detail;
  EXPECT_FALSE(card.passed());
}

// A batch path that carries the previous ray's closest t over as the next ray's bound. The answer checks call
// the single-ray entry points, one ray at a time, and pass it; the batch-calls check calls intersect_batch and
// occluded_batch, as twinray does whenever a plugin has them, and fails it (docs/grading.md, "batch-calls").
// crosscheck finds it too, in process and, now that the worker calls batch functions, isolated.
TEST(GradeBvh4, BatchOnlyBugFailsTheBatchCallsCheck) {
  const Scorecard card = grade_bvh4(bvh4_plugin("batch-stale-tmax"), {"closest-soup", "batch-calls-cornell"});
  EXPECT_EQ(check_named(card, "closest-soup").outcome, Outcome::Pass) << check_lines(card);
  const CheckResult& caught = check_named(card, "batch-calls-cornell");
  EXPECT_EQ(caught.outcome, Outcome::Fail) << check_lines(card);
  EXPECT_EQ(caught.points, 0.0);
  EXPECT_NE(caught.detail.find("answers through intersect_batch and occluded_batch wrong"), std::string::npos)
      << caught.detail;
  EXPECT_FALSE(caught.reproduce.empty());
  EXPECT_FALSE(card.passed());
  EXPECT_TRUE(card.intersect_batch && card.occluded_batch);
  // crosscheck traces batches, so it calls the batch functions, in process and isolated alike.
  for (const char* backend : {"plugin-inprocess:", "plugin:"}) {
    const testing::CommandResult bad =
        testing::run_twinray("crosscheck procedural:soup:2000:7 --backends embree," + std::string(backend) +
                             bvh4_plugin("batch-stale-tmax").string() + " --rays 2000 --kinds uniform");
    EXPECT_EQ(bad.exit_code, 1) << backend << "\n" << bad.output;
    EXPECT_NE(bad.output.find("genuine"), std::string::npos) << bad.output;
  }
}

}  // namespace bvh4_test
}  // namespace twinray::grade
