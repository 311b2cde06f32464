// `twinray grade` against a BVH of another architecture than tests/plugins/scotty_bvh.cpp's: the plain-C
// Karras LBVH of tests/plugins/lbvh_plugin.c (Morton codes, one primitive per leaf, float slab and float
// Moller-Trumbore, neither watertight nor claiming the tie rule). Fairness: the correct build earns every
// point of the test suite. Generality: each of its LBVH-specific bugs loses points in the check expected to
// catch it. docs/grading.md, "An independent plugin: the LBVH".

#include "harness/arbiter/arbiter.h"
#include "core/scene/scene_loader.h"
#include "harness/grade/grade_run.h"
#include "harness/grade/reports.h"
#include "tests/grade_test_util.h"

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

namespace twinray::grade {
namespace lbvh_test {  // named: the unity build puts several test files into one translation unit

std::filesystem::path lbvh_plugin(std::string bug = "") { return testing::test_plugin("lbvh", std::move(bug)); }

using testing::check_lines;
using testing::check_named;
Scorecard grade_lbvh(const std::filesystem::path& plugin, std::vector<std::string> only = {}) {
  return testing::grade_with_test_suite(plugin, std::move(only));
}

TEST(GradeLbvh, CorrectLbvhGetsFullMarks) {
  // Watertightness and the tie rule not claimed (a float Moller-Trumbore leaks through shared edges, and
  // identical triangles are named in traversal order), no batch functions.
  testing::expect_full_marks_without_claims(grade_lbvh(lbvh_plugin()));
}

// The ray that made the arbiter unfair to a float Moller-Trumbore (tolerances.h, kGrazeT): a shadow ray of
// quick's ray-interval-cornell that leaves the Cornell box's tall block at cos 0.0025 to its face (geom 6
// prim 8), with tmin 1e-6 after the face's exact crossing. The float test puts the crossing 1.03e-5 further
// along the ray, inside the interval: rounding of the plane's position over |cos|, not a bug. Before kGrazeT
// its t was ruled "t-off" at 1.006 times the tolerance. The same primitive at ten times the t is still wrong.
TEST(GradeLbvh, GrazingFloatTriangleTestIsNotTOff) {
  const Scene scene = load_scene(testing::source_path("scenes/cornell-box.json"));
  const arbiter::Arbiter judge(scene.geometry);
  Ray ray;
  ray.org = {0x1.c87eep-7f, -0x1.e1df42p-3f, -0x1.3d845ap-4f};
  ray.dir = {0x1.b4cc5ap-3f, 0x1.39ab8cp+0f, -0x1.2cfc4ap-4f};
  ray.tmin = 0x1.05d03p-10f;
  ray.tmax = 1.0f;
  const BackendTraits loose{.counts_traversal = true, .honours_ties = false, .watertight = false};
  Hit answer;
  answer.geom_id = 6;
  answer.prim_id = 8;
  answer.t = 0x1.07b6f8p-10f;  // the LBVH's float Moller-Trumbore
  const arbiter::Ruling r = judge.rule_closest(ray, answer, loose);
  EXPECT_TRUE(r.right) << r.detail;
  answer.t = 0.01f;  // ten times the crossing's t: 9e-3 off, six times the widened tolerance
  const arbiter::Ruling off = judge.rule_closest(ray, answer, loose);
  EXPECT_FALSE(off.right) << off.detail;
  EXPECT_EQ(off.reason, arbiter::Reason::TOff) << off.detail;
}

// The arbiter's shortcut for identical copies (arbiter.cpp): another copy of the exact hit at its t is a tie
// for a backend that does not claim the rule (the LBVH names copies in traversal order), but a copy at a
// wrong t is still wrong, and a backend that claims the rule is still held to the lowest id.
TEST(GradeLbvh, IdenticalCopiesAreTiesButNotBlindly) {
  SceneGeometry g;
  for (std::uint32_t id = 0; id < 2; ++id) {
    TriangleMesh m;
    m.geom_id = id;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.indices = {{0, 1, 2}};
    m.positions.reserve(4);
    g.meshes.push_back(m);
  }
  const arbiter::Arbiter judge(g);
  Ray ray;
  ray.org = {0.25f, 0.25f, 1.0f};
  ray.dir = {0.0f, 0.0f, -1.0f};
  const BackendTraits loose{.counts_traversal = true, .honours_ties = false, .watertight = false};
  const BackendTraits claims{.counts_traversal = true, .honours_ties = true, .watertight = false};
  Hit copy;
  copy.geom_id = 1;
  copy.prim_id = 0;
  copy.t = 1.0f;
  const arbiter::Ruling tie = judge.rule_closest(ray, copy, loose);
  EXPECT_TRUE(tie.right) << tie.detail;
  EXPECT_EQ(tie.reason, arbiter::Reason::Tie) << tie.detail;
  EXPECT_EQ(judge.rule_closest(ray, copy, claims).reason, arbiter::Reason::TieBrokenWrongly);
  copy.t = 0.5f;
  const arbiter::Ruling off = judge.rule_closest(ray, copy, loose);
  EXPECT_FALSE(off.right) << off.detail;
  EXPECT_EQ(off.reason, arbiter::Reason::TOff) << off.detail;
}

using LbvhBug = testing::GradeBugCase;

class GradeLbvhBugs : public ::testing::TestWithParam<LbvhBug> {};

TEST_P(GradeLbvhBugs, LoseThePointsOfTheirCheck) {
  const LbvhBug& b = GetParam();
  testing::expect_caught(grade_lbvh(lbvh_plugin(b.bug), {b.caught_by, b.still_passes}), b);
}

INSTANTIATE_TEST_SUITE_P(
    LbvhBugs, GradeLbvhBugs,
    ::testing::Values(
        // Equal Morton codes without the index tiebreak: nodes over them get ranges that make no tree (a child
        // index past the node array: SIGSEGV in Release, a heap-buffer-overflow report under ASan).
        LbvhBug{"no-tiebreak", "build-identical", Outcome::Crash, "in build", "closest-soup"},
        // A parent's box from its first child only: most of the tree is cut away.
        LbvhBug{"refit-first-child", "closest-soup", Outcome::Fail, "plugin reports a miss", "build-empty"},
        // 32 entries that drop the far child: the nest's inner levels are many more pending entries deep.
        LbvhBug{"stack-32", "deep-tree-nest-capped", Outcome::Fail, "answers wrong", "closest-soup"},
        LbvhBug{"leaf-unsorted", "closest-cornell", Outcome::Fail, "answers wrong", "build-empty"}),
    [](const ::testing::TestParamInfo<LbvhBug>& param) {
      std::string name = param.param.bug;
      for (char& c : name)
        if (c == '-') c = '_';
      return name;
    });

// The two bugs that are no wrong answer: Morton codes whose largest centroid overflows its 10 bits (the keys
// are still sorted, so the tree is valid, only a little worse) and a slab test not cut to the ray's interval
// (every box the ray's line enters is visited). Every answer is right, and the grader says so; only the
// tree-quality figures move.
TEST(GradeLbvh, QualityOnlyBugsKeepEveryAnswerRight) {
  const Scorecard good = grade_lbvh(lbvh_plugin(), {"closest-soup", "tree-quality-soup"});
  const auto nodes_per_ray = [](const Scorecard& card) {
    return check_named(card, "tree-quality-soup").figures.at("nodes_per_ray").at("plugin").get<double>();
  };
  const double good_nodes = nodes_per_ray(good);
  for (const std::string bug : {"morton-overflow", "slab-no-interval"}) {
    const Scorecard card = grade_lbvh(lbvh_plugin(bug), {"closest-soup", "tree-quality-soup"});
    EXPECT_EQ(check_named(card, "closest-soup").outcome, Outcome::Pass) << bug << "\n" << check_lines(card);
    const CheckResult& q = check_named(card, "tree-quality-soup");
    EXPECT_EQ(q.outcome, Outcome::Pass) << bug << "\n" << terminal_check_line(q);
    EXPECT_GT(nodes_per_ray(card), good_nodes) << bug << "\n" << terminal_check_line(q);
  }
}

}  // namespace lbvh_test
}  // namespace twinray::grade
