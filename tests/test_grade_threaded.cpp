// `twinray grade` against a fourth independent BVH: the stackless threaded BVH of tests/plugins/threaded_bvh.c
// (object-median build, one primitive per leaf, six pre-order tables of hit and miss links, one per direction,
// float plane-then-edge-functions triangles, half-b quadratic spheres in double; neither watertight nor the tie
// rule; counts its traversal). Fairness: the correct build earns every point of the test suite. Generality:
// each of its threaded-BVH bugs loses points in the check expected to catch it, or, where no answer is wrong,
// only the figures move. docs/grading.md, "The thirteenth round: a threaded BVH".

#include "harness/grade/grade_run.h"
#include "harness/grade/reports.h"
#include "tests/grade_test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <string>
#include <utility>
#include <vector>

namespace twinray::grade {
namespace threaded_test {  // named: the unity build puts several test files into one translation unit

std::filesystem::path threaded_plugin(std::string bug = "") {
  return testing::test_plugin("threaded", std::move(bug));
}

using testing::check_lines;
using testing::check_named;
Scorecard grade_threaded(const std::filesystem::path& plugin, std::vector<std::string> only = {}) {
  return testing::grade_with_test_suite(plugin, std::move(only));
}

TEST(GradeThreaded, CorrectThreadedBvhGetsFullMarks) {
  // Watertightness and the tie rule not claimed (a float inside test leaks through shared edges, and identical
  // copies are named in walk order), no batch functions.
  testing::expect_full_marks_without_claims(grade_threaded(threaded_plugin()));
}

using ThreadedBug = testing::GradeBugCase;

class GradeThreadedBugs : public ::testing::TestWithParam<ThreadedBug> {};

TEST_P(GradeThreadedBugs, LoseThePointsOfTheirCheck) {
  const ThreadedBug& b = GetParam();
  testing::expect_caught(grade_threaded(threaded_plugin(b.bug), {b.caught_by, b.still_passes}), b);
}

INSTANTIATE_TEST_SUITE_P(
    ThreadedBugs, GradeThreadedBugs,
    ::testing::Values(
        // Escapes by left and right, not by the table's order: where the right child is visited first, the left
        // subtree is never reached.
        ThreadedBug{"swapped-escape", "closest-cornell", Outcome::Fail, "answers wrong", "build-empty"},
        // A sphere hit does not shrink the bound: a farther sphere tested later replaces it.
        ThreadedBug{"sphere-no-shrink", "spheres-sizes", Outcome::Fail, "answers wrong", "closest-soup"},
        // Leaves keep their ranges after the primitives are split by type: only a scene of triangles and spheres
        // together is wrong (the soup, triangles only, is not).
        ThreadedBug{"type-split", "closest-mixed", Outcome::Fail, "answers wrong", "closest-soup"},
        // The root's miss link 0: a ray that misses the scene's box walks back to the root forever, and the
        // per-call limit stops it. Shadow rays inside the Cornell box always enter the root's box.
        ThreadedBug{"root-miss-zero", "closest-soup", Outcome::Timeout, "timed out in intersect", "any-hit-cornell"},
        // Escapes from primitive counts overshoot past leaves of several primitives (box centres that coincide:
        // the coincident clusters, and the Cornell box's quads); the soup's leaves all hold one.
        ThreadedBug{"escape-by-count", "closest-coincident", Outcome::Fail, "answers wrong", "closest-soup"},
        // Any-hit ends the walk at the first box beyond tmax, as if the table were sorted by distance.
        ThreadedBug{"anyhit-break", "any-hit-cornell", Outcome::Fail, "answers wrong", "closest-soup"},
        // The last entry of every table never visited: a scene of one leaf loses everything.
        ThreadedBug{"last-entry-skipped", "closest-cornell", Outcome::Fail, "answers wrong", "build-empty"},
        // The stable quadratic's roots unsorted: the far root of a sphere ahead is reported.
        ThreadedBug{"unsorted-roots", "spheres-sizes", Outcome::Fail, "answers wrong", "closest-soup"},
        // Edge functions of the vertices relative to the ray's origin: right at unit scale (every other check of
        // the quick suite passes it), wrong from a distant viewpoint off every axis, where the products cancel.
        ThreadedBug{"origin-edges", "closest-ball-distant", Outcome::Fail, "answers wrong", "closest-soup"}),
    [](const ::testing::TestParamInfo<ThreadedBug>& param) {
      std::string name = param.param.bug;
      for (char& c : name)
        if (c == '-') c = '_';
      return name;
    });

// The two bugs that are no wrong answer: every ray walks the +x table (back to front for half of them), and
// any-hit walks on to the end of its table after a hit. Every answer is right, and the grader says so; the
// tree-quality check's counts show the extra work (closest hit for the first, any hit for the second).
TEST(GradeThreaded, PerformanceOnlyBugsKeepEveryAnswerRight) {
  const std::vector<std::string> checks = {"closest-soup", "any-hit-cornell", "tree-quality-soup"};
  const auto figure = [](const Scorecard& card, bool any, const char* name) {
    const nlohmann::json& f = check_named(card, "tree-quality-soup").figures;
    return (any ? f.at("any_hit") : f).at(name).at("plugin").get<double>();
  };
  const Scorecard good = grade_threaded(threaded_plugin(), checks);
  const Scorecard fixed = grade_threaded(threaded_plugin("fixed-order"), checks);
  const Scorecard no_exit = grade_threaded(threaded_plugin("anyhit-no-exit"), checks);
  for (const Scorecard* card : {&good, &fixed, &no_exit})
    for (const std::string& name : checks) EXPECT_EQ(check_named(*card, name).outcome, Outcome::Pass) << check_lines(*card);
  EXPECT_GT(figure(fixed, false, "nodes_per_ray"), figure(good, false, "nodes_per_ray")) << check_lines(fixed);
  EXPECT_EQ(figure(no_exit, false, "nodes_per_ray"), figure(good, false, "nodes_per_ray")) << check_lines(no_exit);
  EXPECT_GT(figure(no_exit, true, "nodes_per_ray"), 2.0 * figure(good, true, "nodes_per_ray")) << check_lines(no_exit);
  EXPECT_GT(figure(good, true, "nodes_per_ray"), 0.0) << check_lines(good);
}

}  // namespace threaded_test
}  // namespace twinray::grade
