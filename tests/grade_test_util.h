#pragma once
// The test plugins of tests/plugins and the small grading suite of tests/suites/grading, for the grading
// tests.

#include "harness/grade/grade_run.h"
#include "harness/grade/reports.h"
#include "tests/cli_runner.h"

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace twinray::testing {

// The Scotty3D-style test BVH: "" for the correct one, else a bug's name ("first-hit", "shared-stack", ...;
// tests/plugins/scotty_bvh.cpp lists them).
inline std::filesystem::path scotty_plugin(std::string bug = "") {
  for (char& c : bug)
    if (c == '-') c = '_';
  return std::filesystem::path(TWINRAY_TEST_PLUGIN_DIR) /
         (bug.empty() ? std::string("libtwinray_scotty_plugin.so") : "libtwinray_scotty_" + bug + "_plugin.so");
}

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

}  // namespace twinray::testing
