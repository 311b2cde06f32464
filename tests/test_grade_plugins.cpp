// `twinray grade` against the test plugins of tests/plugins: the correct Scotty3D-style BVH earns full marks,
// each classic bug lands in its category with its outcome (fail, crash, timeout), the cheat is stopped by the
// sandbox, the starter kit earns nothing on correctness without crashing, and two runs give the same
// scorecard. Graded with tests/suites/grading (small scenes, short limits).

#include "harness/grade/grade_run.h"
#include "harness/grade/reports.h"
#include "tests/grade_test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <optional>

namespace twinray::grade {
namespace {

using testing::check_lines;
using testing::check_named;
using testing::scotty_plugin;

Scorecard grade(const std::filesystem::path& plugin, std::vector<std::string> only = {}) {
  return testing::grade_with_test_suite(plugin, std::move(only));
}

TEST(GradePlugins, CorrectPluginGetsFullMarks) {
  const Scorecard card = grade(scotty_plugin());
  EXPECT_TRUE(card.passed()) << check_lines(card);
  EXPECT_EQ(card.score(), card.max_score()) << check_lines(card);
  EXPECT_GT(card.max_score(), 0.0);
  for (const CheckResult& c : card.checks) {
    if (c.category == Category::BatchCalls) {  // no batch functions: not applicable, worth nothing
      EXPECT_EQ(c.outcome, Outcome::Skipped) << terminal_check_line(c);
      EXPECT_EQ(c.max_points, 0.0) << terminal_check_line(c);
      continue;
    }
    EXPECT_EQ(c.outcome, Outcome::Pass) << terminal_check_line(c);
  }
  // It claims watertight and the tie rule, so those checks count.
  EXPECT_GT(check_named(card, "watertight-ball").max_points, 0.0);
  EXPECT_GT(check_named(card, "ties-duplicates").max_points, 0.0);
}

TEST(GradePlugins, StarterKitEarnsNothingOnCorrectnessAndNeverCrashes) {
  const Scorecard card = grade(testing::student_kit_plugin());
  EXPECT_FALSE(card.passed());
  for (const CheckResult& c : card.checks) {
    EXPECT_NE(c.outcome, Outcome::Crash) << terminal_check_line(c);
    EXPECT_NE(c.outcome, Outcome::Timeout) << terminal_check_line(c);
    if (c.category == Category::BatchCalls && !card.intersect_batch && !card.occluded_batch) {
      EXPECT_EQ(c.outcome, Outcome::Skipped) << terminal_check_line(c);  // not applicable, worth nothing
      EXPECT_EQ(c.max_points, 0.0);
    } else if (is_correctness_category(c.category)) {
      EXPECT_EQ(c.outcome, Outcome::Fail) << terminal_check_line(c);
      EXPECT_EQ(c.points, 0.0);
    }
  }
  // It claims nothing, so watertight and ties are reported but worth nothing.
  EXPECT_EQ(check_named(card, "watertight-ball").max_points, 0.0);
  EXPECT_FALSE(check_named(card, "watertight-ball").required);
}

using BugCase = testing::GradeBugCase;

class GradeBugs : public ::testing::TestWithParam<BugCase> {};

TEST_P(GradeBugs, LandInTheirCategoryWithTheirOutcome) {
  const BugCase& b = GetParam();
  testing::expect_caught(grade(scotty_plugin(b.bug), {b.caught_by, b.still_passes}), b);
}

INSTANTIATE_TEST_SUITE_P(
    ClassicBugs, GradeBugs,
    ::testing::Values(BugCase{"first-hit", "closest-soup", Outcome::Fail, "answers wrong", "any-hit-cornell"},
                      BugCase{"early-exit", "closest-soup", Outcome::Fail, "answers wrong", "any-hit-cornell"},
                      BugCase{"slab-no-swap", "closest-cornell", Outcome::Fail, "plugin reports a miss", "build-empty"},
                      BugCase{"lost-primitive", "closest-cornell", Outcome::Fail, "answers wrong", "build-empty"},
                      BugCase{"before-tmin", "ray-interval-soup", Outcome::Fail, "answers wrong", "closest-soup"},
                      BugCase{"zero-direction", "axis-aligned-box", Outcome::Crash, "SIGSEGV", "closest-soup"},
                      BugCase{"infinite-loop", "axis-aligned-box", Outcome::Timeout, "", "closest-soup"},
                      // A race: threads sharing one stack answer wrong or crash, as they meet.
                      BugCase{"shared-stack", "thread-safety-soup", Outcome::Fail,
                              "concurrent answers differ|crashed", "closest-soup"},
                      BugCase{"anyhit-tmax", "any-hit-cornell", Outcome::Fail, "plugin says occluded", "closest-cornell"},
                      // Right primitive, right t: only the attributes give these away (hit_attributes.h).
                      BugCase{"swapped-uv", "closest-cornell", Outcome::Fail, "wrong attributes: u", "any-hit-cornell"},
                      BugCase{"flipped-normal", "closest-soup", Outcome::Fail, "wrong attributes: ng", "any-hit-cornell"},
                      // t = +inf once agreed with every finite t (1e-4 * inf is inf).
                      BugCase{"infinite-t", "closest-soup", Outcome::Fail, "at t inf", "any-hit-cornell"},
                      // 32 entries that drop what does not fit: only a tree deeper than 32 along a ray, with
                      // the closest hit among the last entries pushed (procedural:nest), loses anything.
                      BugCase{"stack-32", "deep-tree-nest", Outcome::Fail, "answers wrong", "closest-soup"},
                      // The same stack in an any-hit traversal (nearer child first): only rays whose every hit is
                      // among the last entries pushed show it (the nest's tunnel).
                      BugCase{"anyhit-stack-32", "deep-tree-nest", Outcome::Fail, "plugin says not occluded",
                              "closest-soup"},
                      BugCase{"backface-cull", "closest-soup", Outcome::Fail, "answers wrong", "spheres-sizes"},
                      // Leaves of 8 to 16 primitives occur where no split separates them: clusters of different
                      // triangles with one bounding box (procedural:coincident-boxes).
                      BugCase{"leaf-count-3bit", "closest-coincident", Outcome::Fail, "answers wrong", "closest-soup"},
                      // The fifth round's: the textbook quadratic in float loses a sphere seen from thousands of
                      // radii away (sphere rays from 2,000 to 20,000 radii); an any-hit that pushes the left
                      // child, then the right, on 32 entries overflows where every inner level is a right child
                      // (the nest's one cone around (-1, -1, -1)).
                      BugCase{"sphere-naive", "spheres-sizes", Outcome::Fail, "answers wrong", "closest-soup"},
                      BugCase{"anyhit-fixed-order-32", "deep-tree-nest-negative", Outcome::Fail,
                              "plugin says not occluded", "closest-soup"},
                      // The sixth round's: an open interval (tmin, tmax) is seen only where t is exact (rays
                      // that end exactly at the Cornell box's walls); a stack that overwrites its oldest
                      // entries only where the hit is in the first subtree pushed (the capped nest); a geom_id
                      // kept in 8 bits only in a scene of more than 256 geometries.
                      BugCase{"open-interval", "ray-interval-cornell", Outcome::Fail, "exact ends of intervals",
                              "closest-soup"},
                      BugCase{"stack-ring-32", "deep-tree-nest-capped", Outcome::Fail, "plugin reports a miss",
                              "closest-soup"},
                      BugCase{"geom-id-8bit", "closest-mixed", Outcome::Fail, "geom_id", "closest-soup"},
                      // Slivers dropped and the rest renumbered: every triangle after the first sliver is named
                      // wrong (procedural:sliver-soup).
                      BugCase{"sliver-drop", "closest-slivers", Outcome::Fail, "answers wrong", "closest-soup"},
                      // The eighth round's. Vertex indices in 16 bits: only a mesh of more than 65,536 vertices
                      // (a soup of 22,000 triangles). Ties resolved by prim_id before geom_id: only where a
                      // later geometry's copy has the lower prim_id (procedural:duplicates-reversed). The sphere
                      // root picked by its sign before the interval check: only rays whose tmin lies inside the
                      // sphere. Mailboxes shared by threads: only concurrent calls.
                      BugCase{"vertex-index-16bit", "closest-soup-large", Outcome::Fail, "answers wrong", "closest-soup"},
                      BugCase{"tie-prim-first", "ties-duplicates-reversed", Outcome::Fail, "answers wrong",
                              "ties-duplicates"},
                      BugCase{"sphere-root-by-zero", "spheres-sizes", Outcome::Fail, "answers wrong",
                              "closest-soup"},
                      BugCase{"shared-mailbox", "thread-safety-soup", Outcome::Fail, "concurrent answers differ",
                              "closest-soup"},
                      BugCase{"bucket-max-drop", "closest-soup", Outcome::Fail, "answers wrong", "build-empty"},
                      BugCase{"bucket-nan-extent", "build-identical", Outcome::Crash, "SIGSEGV", "closest-soup"},
                      BugCase{"leaf-array-8", "closest-coincident", Outcome::Fail, "answers wrong", "closest-soup"},
                      BugCase{"box-unit-dir", "ray-interval-cornell", Outcome::Fail, "answers wrong", "closest-soup"},
                      BugCase{"child-swap-flags", "closest-cornell", Outcome::Fail, "plugin reports a miss",
                              "build-empty"},
                      BugCase{"sphere-stale-prim", "closest-mixed", Outcome::Fail, "which the scene does not have",
                              "closest-soup"},
                      BugCase{"mesh-vertex-offset", "closest-cornell", Outcome::Fail, "answers wrong", "closest-soup"},
                      BugCase{"prune-break", "closest-soup", Outcome::Fail, "answers wrong", "any-hit-cornell"},
                      // A tree in process-global vectors: only a second instance in the same process overwrites
                      // it (the two-instances check's worker holds two).
                      BugCase{"global-tree", "two-instances", Outcome::Fail,
                              "with a second instance of the plugin built on scene 'grid' in the same process",
                              "closest-soup"},
                      // The tenth round's (docs/grading.md, "The tenth round"). Caught by checks that existed:
                      BugCase{"morton-map-dedup", "closest-coincident", Outcome::Fail, "answers wrong", "closest-soup"},
                      BugCase{"quantised-nearest", "spheres-sizes", Outcome::Fail, "answers wrong", "closest-soup"},
                      BugCase{"leaf-clip-exit", "closest-cornell", Outcome::Fail, "plugin reports a miss",
                              "closest-soup"},
                      BugCase{"centre-order-prune", "closest-soup", Outcome::Fail, "answers wrong", "any-hit-cornell"},
                      BugCase{"prim-id-global", "closest-mixed", Outcome::Fail, "which the scene does not have",
                              "closest-soup"},
                      BugCase{"uv-leaf-winding", "closest-soup", Outcome::Fail, "wrong attributes: u",
                              "any-hit-cornell"},
                      BugCase{"shadow-cache-no-tmax", "ray-interval-cornell", Outcome::Fail, "plugin says occluded",
                              "closest-soup"},
                      BugCase{"fma-edges", "watertight-ball", Outcome::Fail, "", "closest-soup"},
                      BugCase{"parallel-strict", "axis-aligned-box", Outcome::Fail, "answers wrong", "closest-soup"},
                      // Caught by what the round added: segments inside a sphere's ball (a solid-ball any-hit
                      // says occluded), and exact ties among copies of flat triangles kept in several leaves
                      // entered at the hit's t (pruning without slack skips the lower prim_id).
                      BugCase{"anyhit-solid-sphere", "spheres-sizes", Outcome::Fail, "plugin says occluded",
                              "closest-soup"},
                      BugCase{"prune-no-slack", "ties-duplicates-box", Outcome::Fail, "answers wrong",
                              "ties-duplicates"},
                      BugCase{"sphere-anyhit-t0", "spheres-sizes", Outcome::Fail, "plugin says occluded",
                              "closest-soup"}),
    [](const ::testing::TestParamInfo<BugCase>& param) {
      std::string name = param.param.bug;
      for (char& c : name)
        if (c == '-') c = '_';
      return name;
    });

TEST(GradePlugins, CheatingPluginIsStoppedBySandbox) {
  const std::filesystem::path mark = "/tmp/twinray-cheat-plugin-escaped";
  std::filesystem::remove(mark);
  const Scorecard card = grade(scotty_plugin("opens-files"), {"closest-soup", "closest-cornell"});
  for (const CheckResult& c : card.checks) {
    EXPECT_EQ(c.outcome, Outcome::Crash) << terminal_check_line(c);
    EXPECT_NE(c.detail.find("sandbox"), std::string::npos) << c.detail;
  }
  EXPECT_FALSE(std::filesystem::exists(mark)) << "the plugin wrote " << mark;
}

// A reported SAH cost below 1 (the cost of the root alone) is no tree's: it must not pass max_sah_ratio as a
// tiny ratio.
TEST(GradePlugins, ImpossibleSahCostFailsTheThreshold) {
  const Scorecard card = grade(scotty_plugin("tiny-sah"), {"closest-soup", "tree-quality-soup"});
  EXPECT_EQ(check_named(card, "closest-soup").outcome, Outcome::Pass) << check_lines(card);
  const CheckResult& c = check_named(card, "tree-quality-soup");
  EXPECT_EQ(c.outcome, Outcome::Fail) << terminal_check_line(c);
  EXPECT_NE(c.detail.find("impossible SAH cost"), std::string::npos) << c.detail;
  // The correct tree passes the same threshold.
  const Scorecard good = grade(scotty_plugin(), {"closest-soup", "tree-quality-soup"});
  EXPECT_EQ(check_named(good, "tree-quality-soup").outcome, Outcome::Pass) << check_lines(good);
}

// What a plugin names itself and says when its build fails reaches the scorecard as one line of plain text:
// no terminal escapes, no line breaks (a fake "pass" line), valid UTF-8.
TEST(GradePlugins, PluginTextCannotBreakTheScorecard) {
  const Scorecard card = grade(TWINRAY_TEST_HOSTILE_BUILD_ESCAPES_PLUGIN, {"build-empty"});
  const CheckResult& c = check_named(card, "build-empty");
  EXPECT_EQ(c.outcome, Outcome::Fail);
  for (const std::string& text : {c.detail, card.plugin_name}) {
    for (const char ch : text) EXPECT_GE(static_cast<unsigned char>(ch), 0x20) << text;
    EXPECT_EQ(text.find("\xc2\x9b"), std::string::npos) << text;  // the C1 escape (CSI)
  }
  EXPECT_NE(c.detail.find("\\x1b[2J"), std::string::npos) << c.detail;  // shown, not obeyed
  EXPECT_NE(card.plugin_name.find("hostile\\x0a"), std::string::npos) << card.plugin_name;
  // Two lines: the check's and its reproduce line.
  const std::string line = terminal_check_line(c);
  EXPECT_EQ(std::count(line.begin(), line.end(), '\n'), 2) << line;
}

// When the check's time runs out while a ray had only just entered the plugin, that ray is not the culprit:
// the reproduce line reruns the check instead of tracing a ray that answers at once.
TEST(GradePlugins, RunningOutOfCheckTimeIsReproducedByTheCheckNotARay) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "twinray-grade-deadline-test";
  std::filesystem::create_directories(dir);
  {
    std::ofstream manifest(dir / "manifest.json");
    // brute force over 20,000 triangles, 8 threads at once, on a time limit far too short for it.
    manifest << R"({"suite": "deadline", "scenes": {"soup": "procedural:soup:20000:7"},
      "checks": [{"name": "threads", "category": "thread-safety", "scene": "soup", "count": 8000, "threads": 8,
                  "repeat": 50, "time_limit": 1.5, "ray_time_limit": 2, "points": 1}]})";
  }
  GradeSettings s;
  s.plugin = TWINRAY_TEST_BRUTE_PLUGIN;
  s.suite = dir.string();
  s.twinray = TWINRAY_BINARY;
  const Scorecard card = run_grade(s);
  const CheckResult& c = check_named(card, "threads");
  EXPECT_EQ(c.outcome, Outcome::Timeout) << terminal_check_line(c);
  EXPECT_NE(c.detail.find("time_limit"), std::string::npos) << c.detail;
  EXPECT_NE(c.reproduce.find("--check threads"), std::string::npos) << c.reproduce;
  EXPECT_EQ(c.reproduce.find(" trace "), std::string::npos) << c.reproduce;
  std::filesystem::remove_all(dir);
}

// A crash that only concurrent calls provoke is the race's, not the ray's: the reproduce line reruns the
// check (tracing the ray it hit would answer normally).
TEST(GradePlugins, CrashUnderConcurrencyIsReproducedByTheCheck) {
  const Scorecard card = grade(scotty_plugin("concurrent-crash"), {"closest-soup", "thread-safety-soup"});
  EXPECT_EQ(check_named(card, "closest-soup").outcome, Outcome::Pass) << check_lines(card);
  const CheckResult& c = check_named(card, "thread-safety-soup");
  EXPECT_EQ(c.outcome, Outcome::Crash) << terminal_check_line(c);
  EXPECT_NE(c.reproduce.find("--check thread-safety-soup"), std::string::npos) << c.reproduce;
  EXPECT_EQ(c.reproduce.find(" trace "), std::string::npos) << c.reproduce;
}

// A suite written for one test into a scratch folder.
std::filesystem::path scratch_suite(const std::string& name, const std::string& manifest) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("twinray-grade-" + name);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "manifest.json") << manifest;
  return dir;
}

Scorecard grade_with(const std::filesystem::path& plugin, const std::filesystem::path& suite,
                     std::optional<double> time_budget = std::nullopt) {
  GradeSettings s;
  s.plugin = plugin;
  s.suite = suite.string();
  s.twinray = TWINRAY_BINARY;
  s.time_budget = time_budget;
  return run_grade(s);
}

// A build that never ends costs one check its time limit, not every check on the scene: a later check that
// would give the same build no more (same scene, same memory limit, a time_limit no longer) reports the same
// timeout at once, naming the check it happened in; one that gives it more time or another memory limit
// builds again.
TEST(GradePlugins, BuildThatTimedOutIsNotRepeatedUnderNoMoreTime) {
  const std::filesystem::path suite = scratch_suite("build-memo", R"({"suite": "build-memo",
    "defaults": {"time_limit": 1, "memory_limit_mib": 1024},
    "scenes": {"soup": "procedural:soup:200:7"},
    "checks": [
      {"name": "build-soup", "category": "build", "scene": "soup", "points": 1},
      {"name": "closest-soup", "category": "closest-hit", "scene": "soup", "rays": "uniform", "count": 100, "points": 1},
      {"name": "any-hit-soup", "category": "any-hit", "scene": "soup", "rays": "uniform", "count": 100, "time_limit": 0.5,
       "points": 1},
      {"name": "closest-soup-more-memory", "category": "closest-hit", "scene": "soup", "rays": "uniform", "count": 100,
       "memory_limit_mib": 1536, "points": 1},
      {"name": "closest-soup-more-time", "category": "closest-hit", "scene": "soup", "rays": "uniform", "count": 100,
       "time_limit": 1.5, "points": 1}]})");
  const Scorecard card = grade_with(TWINRAY_TEST_HOSTILE_BUILD_LOOP_PLUGIN, suite);
  ASSERT_EQ(card.checks.size(), 5u);
  for (const CheckResult& c : card.checks) {
    EXPECT_EQ(c.outcome, Outcome::Timeout) << terminal_check_line(c);
    EXPECT_NE(c.reproduce.find("--check " + c.name), std::string::npos) << c.reproduce;
  }
  for (const char* recalled : {"closest-soup", "any-hit-soup"}) {
    const CheckResult& c = check_named(card, recalled);
    EXPECT_NE(c.detail.find("build timed out in check 'build-soup'"), std::string::npos) << c.detail;
    EXPECT_EQ(c.figures.value("same_build_as", ""), "build-soup");
  }
  for (const char* rebuilt : {"closest-soup-more-memory", "closest-soup-more-time"}) {
    const CheckResult& c = check_named(card, rebuilt);
    EXPECT_FALSE(c.figures.contains("same_build_as")) << terminal_check_line(c);
    EXPECT_NE(c.detail.find("timed out in build"), std::string::npos) << c.detail;
  }
  std::filesystem::remove_all(suite);
}

// The suite's time budget ends the run: the check under way is cut at it (its detail says why) and the checks
// still to run are timeouts that never started; --time-budget overrides the manifest's.
TEST(GradePlugins, TimeBudgetCutsTheRunAndReportsTheRestAsTimeouts) {
  const std::filesystem::path suite = scratch_suite("budget", R"({"suite": "budget", "time_budget": 1.5,
    "defaults": {"time_limit": 1, "memory_limit_mib": 1024},
    "scenes": {"triangle": "procedural:triangle", "soup": "procedural:soup:200:7", "empty": "procedural:empty"},
    "checks": [
      {"name": "build-triangle", "category": "build", "scene": "triangle", "points": 1},
      {"name": "build-soup", "category": "build", "scene": "soup", "points": 1},
      {"name": "build-empty", "category": "build", "scene": "empty", "points": 1}]})");
  const Scorecard card = grade_with(TWINRAY_TEST_HOSTILE_BUILD_LOOP_PLUGIN, suite);
  EXPECT_EQ(card.time_budget, 1.5);
  ASSERT_EQ(card.checks.size(), 3u);
  for (const CheckResult& c : card.checks) EXPECT_EQ(c.outcome, Outcome::Timeout) << terminal_check_line(c);
  EXPECT_NE(card.checks[0].detail.find("time_limit"), std::string::npos) << card.checks[0].detail;
  EXPECT_NE(card.checks[1].detail.find("time_budget of 1.5 s ran out"), std::string::npos) << card.checks[1].detail;
  EXPECT_NE(card.checks[2].detail.find("not run: the suite's time_budget"), std::string::npos) << card.checks[2].detail;
  EXPECT_NE(card.checks[2].reproduce.find("--check build-empty"), std::string::npos) << card.checks[2].reproduce;
  EXPECT_FALSE(card.passed());

  // A correct plugin is not cut by a budget it does not reach, and the flag replaces the manifest's budget.
  const Scorecard good = grade_with(scotty_plugin(), suite, 30.0);
  EXPECT_EQ(good.time_budget, 30.0);
  EXPECT_TRUE(good.passed()) << check_lines(good);
  EXPECT_FALSE(grade_with(scotty_plugin(), suite, 0.0).time_budget.has_value());
  std::filesystem::remove_all(suite);
}

// A check's worker must end as a program that used the plugin ends: destroy(), then the plugin's exit handlers
// and static destructors. A crash or hang there fails a check whose answers were right, with the outcome of
// what happened (crash, timeout), a detail that says so, figure `teardown`, and a reproduce line that reruns
// the check. Threads the plugin leaves running (a spinning pool) end with the worker and are no failure.
TEST(GradePlugins, PluginThatDoesNotEndCleanlyFailsTheCheck) {
  const std::filesystem::path suite = scratch_suite("teardown", R"({"suite": "teardown",
    "defaults": {"time_limit": 10, "ray_time_limit": 1, "memory_limit_mib": 1024},
    "scenes": {"empty": "procedural:empty"},
    "checks": [{"name": "build-empty", "category": "build", "scene": "empty", "points": 1}]})");
  struct Case {
    const char* plugin;
    Outcome outcome;
    const char* words;
  };
  for (const Case& k : {Case{TWINRAY_TEST_HOSTILE_DESTROY_CRASH_PLUGIN, Outcome::Crash, "crashed with SIGSEGV in destroy"},
                        Case{TWINRAY_TEST_HOSTILE_EXIT_HANDLER_CRASH_PLUGIN, Outcome::Crash, "crashed with SIGSEGV in destroy"},
                        Case{TWINRAY_TEST_HOSTILE_EXIT_HANDLER_HANG_PLUGIN, Outcome::Timeout, "exit handlers"}}) {
    const Scorecard card = grade_with(k.plugin, suite);
    const CheckResult& c = check_named(card, "build-empty");
    EXPECT_EQ(c.outcome, k.outcome) << k.plugin << ": " << terminal_check_line(c);
    EXPECT_NE(c.detail.find("probe rays answered right, but at the end of the check"), std::string::npos) << c.detail;
    EXPECT_NE(c.detail.find(k.words), std::string::npos) << c.detail;
    EXPECT_EQ(c.figures.at("teardown").at("outcome"), std::string(to_string(k.outcome))) << c.figures.dump();
    EXPECT_NE(c.reproduce.find("--check build-empty"), std::string::npos) << c.reproduce;
    EXPECT_FALSE(card.passed());
  }
  for (const char* clean : {TWINRAY_TEST_HOSTILE_SPIN_PLUGIN, TWINRAY_TEST_BRUTE_PLUGIN}) {
    const Scorecard card = grade_with(clean, suite);
    const CheckResult& c = check_named(card, "build-empty");
    EXPECT_EQ(c.outcome, Outcome::Pass) << clean << ": " << terminal_check_line(c);
    EXPECT_FALSE(c.figures.contains("teardown")) << c.figures.dump();
  }
  std::filesystem::remove_all(suite);
}

// The third red-team round's bugs that the grader missed or reproduced wrongly before (scotty_bvh.cpp 17-33):
// each is caught by the check made for it, with a reproduce line that replays it, and the correct BVH passes
// the same checks.
TEST(GradePlugins, ThirdRoundBugsAreCaughtAndReproduced) {
  const std::filesystem::path suite = scratch_suite("third-round", R"({"suite": "third-round",
    "defaults": {"time_limit": 30, "memory_limit_mib": 1024, "seed": 3},
    "scenes": {"box": "procedural:box:-2:2", "big": "procedural:sphere-mesh:6",
               "tiny": "procedural:sphere-mesh:3:0:0:0:0.001", "cornell": ")" +
                                                                testing::source_path("scenes/cornell-box.json").string() +
                                                                R"("},
    "checks": [
      {"name": "axis-aligned-box", "category": "axis-aligned", "scene": "box", "count": 3000, "reference": "brute", "points": 1},
      {"name": "closest-big", "category": "closest-hit", "scene": "big", "rays": "uniform", "count": 1000, "points": 1},
      {"name": "closest-tiny", "category": "closest-hit", "scene": "tiny", "rays": "uniform", "count": 1000,
       "reference": "brute", "points": 1},
      {"name": "closest-cornell", "category": "closest-hit", "scene": "cornell", "rays": "camera", "count": 4096,
       "reference": "brute", "points": 1}]})");
  const auto grade_one = [&](const std::string& bug, const std::string& check) {
    GradeSettings s;
    s.plugin = scotty_plugin(bug);
    s.suite = suite.string();
    s.only = {check};
    s.twinray = TWINRAY_BINARY;
    return run_grade(s);
  };
  // NaN from 0 * inf in a slab test: only rays exactly in a box's plane show it (axis-aligned, through vertices).
  // A 16-bit primitive index: only a mesh of more than 65,536 triangles. A fixed epsilon: only a tiny mesh.
  for (const auto& [bug, check] : std::vector<std::pair<std::string, std::string>>{
           {"nan-slab", "axis-aligned-box"}, {"index-16bit", "closest-big"}, {"mt-epsilon", "closest-tiny"}}) {
    const Scorecard card = grade_one(bug, check);
    const CheckResult& c = check_named(card, check);
    EXPECT_EQ(c.outcome, Outcome::Fail) << bug << ": " << terminal_check_line(c);
    EXPECT_NE(c.reproduce.find(" trace "), std::string::npos) << c.reproduce;
    EXPECT_EQ(c.figures.value("replays_alone", false), true) << c.figures.dump();
    EXPECT_EQ(check_named(grade_one("", check), check).outcome, Outcome::Pass) << check;
  }
  // A bound carried over from the thread's previous ray: the first wrong ray, asked alone as the reproduce line
  // would, is answered right, so the reproduce line reruns the check instead.
  const Scorecard cache = grade_one("last-ray-cache", "closest-cornell");
  const CheckResult& c = check_named(cache, "closest-cornell");
  EXPECT_EQ(c.outcome, Outcome::Fail) << terminal_check_line(c);
  EXPECT_NE(c.detail.find("depend on the rays asked before"), std::string::npos) << c.detail;
  EXPECT_NE(c.reproduce.find("--check closest-cornell"), std::string::npos) << c.reproduce;
  EXPECT_EQ(c.figures.value("replays_alone", true), false) << c.figures.dump();
  std::filesystem::remove_all(suite);
}

// Child node indices kept in 16 bits go wrong only past 65,536 nodes: a 327,680-triangle mesh's build check
// catches it (the default suite's million-triangle build and dragon checks do too), and the correct BVH passes.
TEST(GradePlugins, SixteenBitNodeIndexIsCaughtOnALargeMesh) {
  const std::filesystem::path suite = scratch_suite("node-index", R"({"suite": "node-index",
    "defaults": {"time_limit": 60, "memory_limit_mib": 2048, "seed": 3},
    "scenes": {"large": "procedural:sphere-mesh:7"},
    "checks": [{"name": "build-large", "category": "build", "scene": "large", "points": 1}]})");
  const CheckResult bad = check_named(grade_with(scotty_plugin("node-index-16bit"), suite), "build-large");
  EXPECT_NE(bad.outcome, Outcome::Pass) << terminal_check_line(bad);
  EXPECT_EQ(bad.points, 0.0);
  const CheckResult good = check_named(grade_with(scotty_plugin(), suite), "build-large");
  EXPECT_EQ(good.outcome, Outcome::Pass) << terminal_check_line(good);
  std::filesystem::remove_all(suite);
}

// A plugin that writes over the shared memory its worker answers through is stopped at the first answer the
// worker cannot give, as a crash, rather than waited for until the check's time limit.
TEST(GradePlugins, PluginWritingOverTheWorkersMemoryCrashesTheCheckAtOnce) {
  const Scorecard card = grade(TWINRAY_TEST_HOSTILE_SCRIBBLE_PLUGIN, {"build-empty", "closest-soup"});
  for (const CheckResult& c : card.checks) {
    EXPECT_EQ(c.outcome, Outcome::Crash) << terminal_check_line(c);
    EXPECT_NE(c.detail.find("wrote over the worker's shared memory"), std::string::npos) << c.detail;
  }
}

// A plugin that reports a mesh's place in the mesh array as its geom_id is right wherever meshes are numbered
// 0, 1, 2, ...; the quick suite's closest-mixed (spheres numbered between two meshes) catches it, and the
// correct BVH passes it.
TEST(GradePlugins, QuickSuiteCatchesAMeshIndexReportedAsGeomId) {
  GradeSettings s;
  s.plugin = scotty_plugin("mesh-index-id");
  s.suite = "quick";
  s.only = {"closest-soup", "closest-mixed"};
  s.twinray = TWINRAY_BINARY;
  const Scorecard card = run_grade(s);
  EXPECT_EQ(check_named(card, "closest-soup").outcome, Outcome::Pass) << check_lines(card);  // one mesh, geom_id 0
  EXPECT_EQ(check_named(card, "closest-mixed").outcome, Outcome::Fail) << check_lines(card);
  s.plugin = scotty_plugin();
  s.only = {"closest-mixed"};
  const Scorecard good = run_grade(s);
  EXPECT_EQ(check_named(good, "closest-mixed").outcome, Outcome::Pass) << check_lines(good);
}

// The checks made for the fifth round's bugs fail no correct BVH: the brute-force plugin (no tree at all, the
// textbook's robust sphere test) passes them as the correct scotty does (CorrectPluginGetsFullMarks).
TEST(GradePlugins, BruteForcePassesTheFifthRoundsChecks) {
  const Scorecard card = grade(TWINRAY_TEST_BRUTE_PLUGIN, {"spheres-sizes", "deep-tree-nest-negative"});
  ASSERT_EQ(card.checks.size(), 2u);
  for (const CheckResult& c : card.checks) EXPECT_EQ(c.outcome, Outcome::Pass) << terminal_check_line(c);
}

// The checks made for the sixth round's bugs fail no correct BVH either: the brute-force plugin passes the
// interval ends, the capped nest and the scene of 301 geometries.
TEST(GradePlugins, BruteForcePassesTheSixthRoundsChecks) {
  const Scorecard card =
      grade(TWINRAY_TEST_BRUTE_PLUGIN, {"ray-interval-cornell", "deep-tree-nest-capped", "closest-mixed"});
  ASSERT_EQ(card.checks.size(), 3u);
  for (const CheckResult& c : card.checks) EXPECT_EQ(c.outcome, Outcome::Pass) << terminal_check_line(c);
}

// The checks made for the eighth round's bugs fail no correct BVH: the brute-force plugin passes the sphere rays
// whose tmin lies inside the sphere, the soup of 66,000 vertices and the reversed duplicates (it honours the tie
// rule, lower geom_id first).
TEST(GradePlugins, BruteForcePassesTheEighthRoundsChecks) {
  const Scorecard card =
      grade(TWINRAY_TEST_BRUTE_PLUGIN, {"spheres-sizes", "closest-soup-large", "ties-duplicates-reversed"});
  ASSERT_EQ(card.checks.size(), 3u);
  for (const CheckResult& c : card.checks) EXPECT_EQ(c.outcome, Outcome::Pass) << terminal_check_line(c);
}

// A second instance that is wrong on its own scene, not because of the first (scotty bug 82 drops one triangle of
// each of the grid's squares whoever builds it): asked of one instance built on that scene alone, the ray gets
// the same wrong answer, so the verdict says the plugin is wrong on that scene and the reproduce line traces it
// there, rather than blaming the instances' independence.
TEST(GradePlugins, SecondInstanceWrongOnItsOwnSceneIsTracedThere) {
  const Scorecard card = grade(scotty_plugin("morton-map-dedup"), {"two-instances"});
  const CheckResult& c = check_named(card, "two-instances");
  EXPECT_EQ(c.outcome, Outcome::Fail) << terminal_check_line(c);
  EXPECT_NE(c.detail.find("alone answers the same: the plugin is wrong on that scene itself"), std::string::npos)
      << c.detail;
  EXPECT_NE(c.reproduce.find(" trace procedural:grid:"), std::string::npos) << c.reproduce;
  EXPECT_TRUE(c.figures.value("replays_alone", false)) << terminal_check_line(c);
}

// The checks made for the tenth round's bugs fail no correct BVH: the brute-force plugin passes the sphere
// segments that start and end inside a ball and the ties among 24 copies of each flat triangle of a box.
TEST(GradePlugins, BruteForcePassesTheTenthRoundsChecks) {
  const Scorecard card = grade(TWINRAY_TEST_BRUTE_PLUGIN, {"spheres-sizes", "ties-duplicates-box"});
  ASSERT_EQ(card.checks.size(), 2u);
  for (const CheckResult& c : card.checks) EXPECT_EQ(c.outcome, Outcome::Pass) << terminal_check_line(c);
}

// Instances of a correct plugin are independent: the brute-force plugin (whose state is all in its instance)
// passes the two-instances check, its first instance answering for the soup after a second was built on a grid
// in the same worker, and the second for the grid.
TEST(GradePlugins, BruteForcePassesTheTwoInstancesCheck) {
  const Scorecard card = grade(TWINRAY_TEST_BRUTE_PLUGIN, {"two-instances"});
  ASSERT_EQ(card.checks.size(), 1u);
  EXPECT_EQ(card.checks[0].outcome, Outcome::Pass) << terminal_check_line(card.checks[0]);
  EXPECT_EQ(card.checks[0].figures.value("wrong", -1), 0) << terminal_check_line(card.checks[0]);
  // The second instance answered for its own scene as well.
  EXPECT_GT(card.checks[0].figures.value("second_instance_rays", 0), 0) << terminal_check_line(card.checks[0]);
  EXPECT_EQ(card.checks[0].figures.value("second_instance_wrong", -1), 0) << terminal_check_line(card.checks[0]);
}

// A tree built lazily by the first query, without a lock (scotty bug 54), races only while the first calls
// into a fresh instance run at once: the thread-safety check's first round is concurrent, before the
// single-threaded answers it is compared with. Whether two builders meet inside the build, and whether their
// pushes interleave, is the scheduler's choice: the test build of bug 54 makes sure they do (it sleeps inside
// its first nodes and waits for a second builder), so the verdict does not depend on the machine's load
// (this test was flaky on 20,000 triangles under heavy load before). The correct BVH and the brute-force
// plugin pass.
TEST(GradePlugins, LazyBuildRacesInTheFirstConcurrentRound) {
  const std::filesystem::path suite = scratch_suite("lazy-build", R"({"suite": "lazy-build",
    "defaults": {"time_limit": 20, "memory_limit_mib": 1024, "seed": 3},
    "scenes": {"soup": "procedural:soup:20000:7", "small": "procedural:soup:500:7"},
    "checks": [
      {"name": "threads", "category": "thread-safety", "scene": "soup", "count": 2048, "threads": 8, "repeat": 1,
       "min_seconds": 0, "points": 1},
      {"name": "threads-small", "category": "thread-safety", "scene": "small", "count": 512, "threads": 8,
       "repeat": 1, "min_seconds": 0, "points": 1}]})");
  const auto one = [&](const std::filesystem::path& plugin, const std::string& check) {
    GradeSettings s;
    s.plugin = plugin;
    s.suite = suite.string();
    s.only = {check};
    s.twinray = TWINRAY_BINARY;
    return check_named(run_grade(s), check);
  };
  const CheckResult lazy = one(scotty_plugin("lazy-build"), "threads");
  EXPECT_NE(lazy.outcome, Outcome::Pass) << terminal_check_line(lazy);
  EXPECT_EQ(lazy.points, 0.0);
  EXPECT_NE(lazy.reproduce.find("--check threads"), std::string::npos) << lazy.reproduce;
  EXPECT_EQ(one(scotty_plugin(), "threads").outcome, Outcome::Pass);
  EXPECT_EQ(one(TWINRAY_TEST_BRUTE_PLUGIN, "threads-small").outcome, Outcome::Pass);
  std::filesystem::remove_all(suite);
}

TEST(GradePlugins, SameScorecardTwice) {
  const std::vector<std::string> checks = {"closest-soup", "ray-interval-soup", "axis-aligned-box", "watertight-ball"};
  const Scorecard a = grade(scotty_plugin("lost-primitive"), checks), b = grade(scotty_plugin("lost-primitive"), checks);
  ASSERT_EQ(a.checks.size(), b.checks.size());
  for (std::size_t i = 0; i < a.checks.size(); ++i) {
    EXPECT_EQ(a.checks[i].outcome, b.checks[i].outcome);
    EXPECT_EQ(a.checks[i].points, b.checks[i].points);
    EXPECT_EQ(a.checks[i].detail, b.checks[i].detail);
    EXPECT_EQ(a.checks[i].reproduce, b.checks[i].reproduce);
    EXPECT_EQ(a.checks[i].figures, b.checks[i].figures);
  }
  EXPECT_EQ(a.score(), b.score());
}

TEST(GradePlugins, ReproduceLineWorksWhenPasted) {
  const Scorecard card = grade(scotty_plugin("lost-primitive"), {"closest-soup"});
  const CheckResult& c = check_named(card, "closest-soup");
  ASSERT_EQ(c.outcome, Outcome::Fail);
  ASSERT_NE(c.reproduce.find(" trace "), std::string::npos) << c.reproduce;
  // The line replays the first wrong ray: the plugin and the reference disagree on it, genuinely.
  const testing::CommandResult r = testing::run_command("CI=true " + c.reproduce);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("closest hit genuine"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace twinray::grade
