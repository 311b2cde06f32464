#pragma once
// The test plugins of tests/plugins and the small grading suite of tests/suites/grading, for the grading
// tests.

#include "tests/cli_runner.h"

#include <filesystem>
#include <string>

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

}  // namespace twinray::testing
