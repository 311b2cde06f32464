#pragma once
// The test plugins of tests/plugins and the small grading suite of tests/suites/grading, for the grading
// tests.

#include "harness/grade/grade_run.h"
#include "harness/grade/reports.h"
#include "tests/cli_runner.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace twinray::testing {

// A test plugin of tests/plugins/CMakeLists.txt: `family` "scotty", "bvh4", "lbvh", "brute", ...; `bug` "" for
// the correct build, else a bug's name, with - or _ ("first-hit"; each plugin's source lists its bugs).
inline std::filesystem::path test_plugin(const std::string& family, std::string bug = "") {
  for (char& c : bug)
    if (c == '-') c = '_';
  return std::filesystem::path(TWINRAY_TEST_PLUGIN_DIR) /
         ("libtwinray_" + family + (bug.empty() ? "" : "_" + bug) + "_plugin.so");
}

// The Scotty3D-style test BVH (tests/plugins/scotty_bvh.cpp).
inline std::filesystem::path scotty_plugin(std::string bug = "") { return test_plugin("scotty", std::move(bug)); }
// The 4-wide SIMD test BVH (tests/plugins/bvh4_plugin.cpp).
inline std::filesystem::path bvh4_plugin(std::string bug = "") { return test_plugin("bvh4", std::move(bug)); }

inline std::filesystem::path student_kit_plugin() { return TWINRAY_TEST_STUDENT_KIT_PLUGIN; }

inline std::filesystem::path grading_test_suite() { return source_path("tests/suites/grading"); }

// Grades `plugin` with the test suite (all checks, or only those named), through the real program so that
// reproduce lines start it as `twinray grade` writes them.
inline grade::Scorecard grade_with_test_suite(const std::filesystem::path& plugin, std::vector<std::string> only = {}) {
  grade::GradeSettings s;
  s.plugin = plugin;
  s.suite = grading_test_suite().string();
  s.only = std::move(only);
  s.twinray = TWINRAY_BINARY;
  return grade::run_grade(s);
}

inline const grade::CheckResult& check_named(const grade::Scorecard& card, const std::string& name) {
  for (const grade::CheckResult& c : card.checks)
    if (c.name == name) return c;
  throw std::logic_error("no check " + name);
}

// Every check's terminal line, for failure messages.
inline std::string check_lines(const grade::Scorecard& card) {
  std::string s;
  for (const grade::CheckResult& c : card.checks) s += grade::terminal_check_line(c);
  return s;
}

// A broken test plugin and where it must be caught: the check that must fail it (with this outcome and these
// words in its detail) and a check of another category it does not touch, which must still pass.
struct GradeBugCase {
  std::string bug;
  std::string caught_by;
  grade::Outcome outcome;
  std::string detail_words;  // words the detail must hold; "a|b": either
  std::string still_passes;
};

// The scorecard of the two checks of `b`: the first lost with its points and a reproduce line, and the grader
// went on (in a fresh worker after a crash or timeout) to pass the untouched one.
inline void expect_caught(const grade::Scorecard& card, const GradeBugCase& b) {
  const grade::CheckResult& caught = check_named(card, b.caught_by);
  EXPECT_EQ(caught.outcome, b.outcome) << grade::terminal_check_line(caught);
  EXPECT_EQ(caught.points, 0.0);
  // detail_words may list alternatives, "a|b" (a race that answers wrong or crashes, as the threads meet).
  bool named = false;
  for (std::size_t from = 0;;) {
    const std::size_t bar = b.detail_words.find('|', from);
    named = named || caught.detail.find(b.detail_words.substr(from, bar - from)) != std::string::npos;
    if (bar == std::string::npos) break;
    from = bar + 1;
  }
  EXPECT_TRUE(named) << "expected \"" << b.detail_words << "\" in: " << caught.detail;
  EXPECT_FALSE(caught.reproduce.empty());
  EXPECT_FALSE(card.passed());
  EXPECT_EQ(check_named(card, b.still_passes).outcome, grade::Outcome::Pass) << check_lines(card);
}

// Full marks on the test suite for a correct plugin that claims neither watertightness nor the tie rule and has no
// batch functions (the LBVH, the threaded BVH): the watertight and ties checks reported, worth nothing and not
// required; batch-calls skipped; every other check passed, except the complexity check's outcome: it is judged
// by time (the worker's CPU time since the thirteenth round) and worth 0 points in the test suite, and on a loaded
// machine a correct tree has measured close to its threshold (docs/grading.md, "The thirteenth round: CPU
// time"), so only its points count here (the score); GradeMeasure.ComplexityTellsATreeFromBruteForce tests what
// it tells apart.
inline void expect_full_marks_without_claims(const grade::Scorecard& card) {
  EXPECT_TRUE(card.passed()) << check_lines(card);
  EXPECT_EQ(card.score(), card.max_score()) << check_lines(card);
  EXPECT_GT(card.max_score(), 0.0);
  for (const grade::CheckResult& c : card.checks) {
    if (c.category == grade::Category::Watertight || c.category == grade::Category::Ties) {
      EXPECT_EQ(c.max_points, 0.0) << grade::terminal_check_line(c);
      EXPECT_FALSE(c.required) << grade::terminal_check_line(c);
      continue;
    }
    if (c.category == grade::Category::BatchCalls) {
      EXPECT_EQ(c.outcome, grade::Outcome::Skipped) << grade::terminal_check_line(c);
      EXPECT_EQ(c.max_points, 0.0) << grade::terminal_check_line(c);
      continue;
    }
    if (c.category == grade::Category::Complexity) continue;
    EXPECT_EQ(c.outcome, grade::Outcome::Pass) << grade::terminal_check_line(c);
  }
}

}  // namespace twinray::testing
