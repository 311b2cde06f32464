// The command-line contract of `twinray grade` and `twinray trace` (docs/cli.md, docs/grading.md): exit codes,
// output files that validate against their formats, and nothing left behind on bad input.

#include "tests/format_validators.h"
#include "harness/grade/time_calibration.h"
#include "tests/grade_test_util.h"

#include <fmt/core.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace twinray::testing {
namespace {

nlohmann::json read_json_file(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

std::string grade_args(const std::filesystem::path& plugin, const std::string& more) {
  return "grade " + quoted(plugin) + " --suite " + quoted(grading_test_suite()) + " " + more;
}

TEST(GradeCli, CorrectPluginExitsZeroWithValidOutputs) {
  const auto dir = scratch_dir("grade-cli-ok");
  const CommandResult r = run_twinray(grade_args(scotty_plugin(), "--json " + quoted(dir / "card.json") + " --gradescope " +
                                                                       quoted(dir / "results.json") + " --junit " +
                                                                       quoted(dir / "junit.xml") + " --out " + quoted(dir / "images")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("verdict: PASS"), std::string::npos) << r.output;
  const nlohmann::json card = read_json_file(dir / "card.json");
  EXPECT_TRUE(card.at("passed").get<bool>());
  EXPECT_EQ(card.at("score"), card.at("max_score"));
  EXPECT_EQ(validate_gradescope(dir / "results.json").exit_code, 0);
  EXPECT_EQ(validate_junit(dir / "junit.xml").exit_code, 0);
  EXPECT_TRUE(std::filesystem::is_regular_file(dir / "images" / "closest-cornell.png"));
}

TEST(GradeCli, FailuresExitOneAndTheirFilesValidate) {
  const auto dir = scratch_dir("grade-cli-fail");
  // A crash, a failure and passes in one run: every kind of testcase in the JUnit file.
  const CommandResult r =
      run_twinray(grade_args(scotty_plugin("zero-direction"), "--check axis-aligned-box --check closest-soup --check build-empty "
                                                              "--json " + quoted(dir / "card.json") + " --gradescope " +
                                                              quoted(dir / "results.json") + " --junit " + quoted(dir / "junit.xml")));
  ASSERT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("CRASH"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("reproduce: "), std::string::npos) << r.output;
  const CommandResult gs = validate_gradescope(dir / "results.json");
  EXPECT_EQ(gs.exit_code, 0) << gs.output;
  const CommandResult ju = validate_junit(dir / "junit.xml");
  EXPECT_EQ(ju.exit_code, 0) << ju.output;
  const nlohmann::json card = read_json_file(dir / "card.json");
  EXPECT_FALSE(card.at("passed").get<bool>());
  EXPECT_EQ(card.at("checks").size(), 3u);
}

// A plugin whose every build hangs, with a budget of one second for the run: exit 1 within about that, and
// every output file complete and valid, the checks that never ran included.
TEST(GradeCli, TimeBudgetEndsTheRunWithCompleteValidOutputs) {
  const auto dir = scratch_dir("grade-cli-budget");
  const CommandResult r = run_twinray(grade_args(TWINRAY_TEST_HOSTILE_BUILD_LOOP_PLUGIN,
                                                 "--time-budget 1 --json " + quoted(dir / "card.json") + " --gradescope " +
                                                     quoted(dir / "results.json") + " --junit " + quoted(dir / "junit.xml")));
  ASSERT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("not run: the suite's time_budget of 1 s ran out"), std::string::npos) << r.output;
  const nlohmann::json card = read_json_file(dir / "card.json");
  EXPECT_EQ(card.at("time_budget"), 1.0);
  const nlohmann::json manifest = read_json_file(grading_test_suite() / "manifest.json");
  EXPECT_EQ(card.at("checks").size(), manifest.at("checks").size());
  const CommandResult gs = validate_gradescope(dir / "results.json");
  EXPECT_EQ(gs.exit_code, 0) << gs.output;
  const CommandResult ju = validate_junit(dir / "junit.xml");
  EXPECT_EQ(ju.exit_code, 0) << ju.output;
}

// --time-scale multiplies the suite's limits (the test suite's time_limit is 4 s): a build that never returns
// is cut after 0.1 x 4 s, the scorecard says so, and the reproduce line replays under the same limits.
TEST(GradeCli, TimeScaleMultipliesTheSuitesLimits) {
  const auto dir = scratch_dir("grade-cli-time-scale");
  const CommandResult r = run_twinray(grade_args(TWINRAY_TEST_HOSTILE_BUILD_LOOP_PLUGIN,
                                                 "--check build-empty --time-scale 0.1 --json " + quoted(dir / "card.json")));
  ASSERT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("time limits x 0.1"), std::string::npos) << r.output;
  const nlohmann::json card = read_json_file(dir / "card.json");
  EXPECT_EQ(card.at("time_scale"), 0.1);
  const nlohmann::json& check = card.at("checks").at(0);
  EXPECT_EQ(check.at("outcome"), "timeout") << check.dump();
  // 0.4 s scaled against 4 s unscaled: 3 s leaves room for starting the worker on a busy machine.
  EXPECT_LT(check.at("seconds").get<double>(), 3.0) << check.dump();
  EXPECT_NE(check.at("reproduce").get<std::string>().find("--time-scale 0.1"), std::string::npos) << check.dump();
}

// --time-scale auto times a fixed workload and takes the factor from the ladder of time_calibration.h: recorded
// with its measure, never below 1, and repeated as a number in reproduce lines (a replay does not recalibrate).
TEST(GradeCli, TimeScaleAutoIsMeasuredRecordedAndRepeated) {
  const auto dir = scratch_dir("grade-cli-time-scale-auto");
  // A missed threshold: its reproduce line is a `grade --check` line, which carries the factor (trace lines have
  // no time limits to scale).
  const CommandResult r = run_twinray(grade_args(scotty_plugin("tiny-sah"),
                                                 "--check tree-quality-soup --time-scale auto --json " + quoted(dir / "card.json")));
  ASSERT_EQ(r.exit_code, 0) << r.output;  // the check is not required
  EXPECT_NE(r.output.find("--time-scale auto: the reference workload took"), std::string::npos) << r.output;
  const nlohmann::json card = read_json_file(dir / "card.json");
  const nlohmann::json& measure = card.at("time_scale_auto");
  const double measured = measure.at("measured_seconds").get<double>(), reference = measure.at("reference_seconds").get<double>();
  EXPECT_GT(measured, 0.0);
  EXPECT_EQ(reference, grade::kReferenceWorkloadSeconds);
  const double scale = card.at("time_scale").get<double>();
  EXPECT_EQ(scale, grade::quantised_time_scale(measured / reference)) << measure.dump();
  EXPECT_EQ(measure.at("scale").get<double>(), scale);
  EXPECT_GE(scale, 1.0);
  ASSERT_EQ(card.at("checks").at(0).at("outcome"), "fail") << card.dump();
  const std::string reproduce = card.at("checks").at(0).at("reproduce").get<std::string>();
  EXPECT_NE(reproduce.find("--check tree-quality-soup"), std::string::npos) << reproduce;
  if (scale != 1.0) {
    EXPECT_NE(reproduce.find(fmt::format("--time-scale {:g}", scale)), std::string::npos) << reproduce;
  }
  EXPECT_EQ(reproduce.find("auto"), std::string::npos) << reproduce;
  // Without auto the key is there, null (keys are only ever added).
  const CommandResult plain = run_twinray(grade_args(scotty_plugin(), "--check build-empty --json " + quoted(dir / "plain.json")));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_TRUE(read_json_file(dir / "plain.json").at("time_scale_auto").is_null());
}

// The ladder: 1 up to a quarter above the reference, then the smallest rung that covers the ratio less that
// quarter; never above 100.
TEST(GradeCli, TimeScaleLadder) {
  EXPECT_EQ(grade::quantised_time_scale(0.2), 1.0);
  EXPECT_EQ(grade::quantised_time_scale(1.0), 1.0);
  EXPECT_EQ(grade::quantised_time_scale(1.25), 1.0);
  EXPECT_EQ(grade::quantised_time_scale(1.3), 1.5);
  EXPECT_EQ(grade::quantised_time_scale(1.875), 1.5);
  EXPECT_EQ(grade::quantised_time_scale(1.9), 2.0);
  EXPECT_EQ(grade::quantised_time_scale(10.0), 8.0);
  EXPECT_EQ(grade::quantised_time_scale(10.1), 12.0);
  EXPECT_EQ(grade::quantised_time_scale(1e6), 100.0);
}

TEST(GradeCli, BadInputExitsTwoAndLeavesNothing) {
  const auto dir = scratch_dir("grade-cli-bad");
  const std::string outputs = "--json " + quoted(dir / "card.json") + " --gradescope " + quoted(dir / "results.json") +
                              " --junit " + quoted(dir / "junit.xml") + " --out " + quoted(dir / "images");
  const std::string missing = quoted(dir / "no-such-plugin.so");
  const std::pair<std::string, std::string> cases[] = {
      {"grade " + missing + " " + outputs, "no-such-plugin.so"},
      {grade_args(scotty_plugin(), "--check no-such-check " + outputs), "no-such-check"},
      {"grade " + quoted(scotty_plugin()) + " --suite no-such-suite " + outputs, "no-such-suite"},
      {"grade " + quoted(std::filesystem::path(TWINRAY_TEST_WRONG_ABI_PLUGIN)) + " --suite quick " + outputs, "ABI"},
      {grade_args(scotty_plugin(), "--json " + quoted(dir / "missing-folder" / "card.json")), "missing-folder"},
      {grade_args(scotty_plugin(), "--time-budget -1 " + outputs), "--time-budget"},
      {grade_args(scotty_plugin(), "--time-scale 0 " + outputs), "--time-scale"},
      {grade_args(scotty_plugin(), "--time-scale fast " + outputs), "--time-scale"},
      {grade_args(scotty_plugin(), "--time-scale 2x " + outputs), "--time-scale"},
  };
  for (const auto& [args, words] : cases) {
    const CommandResult r = run_twinray(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(words), std::string::npos) << r.output;
    EXPECT_TRUE(std::filesystem::is_empty(dir)) << args;
  }
}

TEST(GradeCli, ListsASuite) {
  const CommandResult r = run_twinray("grade --suite quick --list");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("closest-cornell-camera"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("thread-safety"), std::string::npos) << r.output;
}

TEST(TraceCli, AnswersSideBySideWithVisitOrderAndJson) {
  const auto dir = scratch_dir("trace-cli");
  const CommandResult r = run_twinray("trace procedural:grid:4:4 --backends bvh,embree,brute,plugin:" +
                                      quoted(scotty_plugin()) + " --ray '0.5 0.25 3 0 -0 -1 0 inf' --json " +
                                      quoted(dir / "trace.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("t 3 (0x1.8p+1)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("nodes entered by the closest-hit query"), std::string::npos) << r.output;
  const nlohmann::json j = read_json_file(dir / "trace.json");
  EXPECT_TRUE(j.at("agree").get<bool>());
  EXPECT_EQ(j.at("ray").at("hex"), "0x1p-1 0x1p-2 0x1.8p+1 0x0p+0 -0x0p+0 -0x1p+0 0x0p+0 inf");
  ASSERT_EQ(j.at("backends").size(), 4u);
  for (const auto& b : j.at("backends")) {
    EXPECT_EQ(b.at("closest").at("t_hex"), "0x1.8p+1") << b;
    EXPECT_EQ(b.at("closest").at("prim_id"), 0) << b;
    EXPECT_TRUE(b.at("occluded").get<bool>()) << b;
    if (b.at("name") != "bvh") {
      EXPECT_EQ(b.at("t_ulps_from_reference"), 0) << b;  // the same primitive and t as bvh
    }
  }
  EXPECT_NE(r.output.find("vs bvh: closest hit identical (the same t as bvh), any-hit agree"), std::string::npos)
      << r.output;
  // bvh lists the nodes it entered, root first; a counting plugin its counts.
  const auto& visits = j.at("backends")[0].at("visits").at("closest");
  ASSERT_FALSE(visits.empty());
  EXPECT_EQ(visits[0].at("node"), 0);
  EXPECT_TRUE(visits.back().at("leaf").get<bool>());
  EXPECT_GT(j.at("backends")[3].at("closest_stats").at("nodes_visited").get<int>(), 0);
}

TEST(TraceCli, PluginCrashIsAnAnswerNotACrash) {
  const CommandResult r = run_twinray("trace procedural:box:-2:2 --backends embree,plugin:" +
                                      quoted(scotty_plugin("zero-direction")) + " --ray '0.5 0.5 -5 0 0 1 0 inf'");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("SIGSEGV"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("geom 0"), std::string::npos) << r.output;  // embree's answer is still there
}

TEST(TraceCli, BadRaysAndScenesAreBadInput) {
  for (const char* args : {"trace procedural:triangle --ray '1 2 3'", "trace procedural:triangle --ray '1 2 3 4 5 6 7 x'",
                           "trace procedural:nothing --ray '0 0 1 0 0 -1 0 inf'",
                           "trace procedural:triangle --backends nope --ray '0 0 1 0 0 -1 0 inf'"}) {
    const CommandResult r = run_twinray(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
  }
}

}  // namespace
}  // namespace twinray::testing
