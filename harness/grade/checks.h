#pragma once
// The checks: one function per category family, each given its spec, its scene (with the reference
// backends) and a way to start the plugin, and returning a verdict. A plugin failure (crash, timeout,
// contract violation) is not caught here: it propagates to the suite runner (grade_run.h), which turns it
// into the check's outcome. docs/grading.md describes what every category checks and why.

#include "core/image/image.h"
#include "harness/grade/failed_builds.h"
#include "harness/grade/grade_scene.h"
#include "harness/grade/plugin_launcher.h"
#include "harness/grade/suite.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace twinray::grade {

struct CheckEnvironment {
  const Suite& suite;
  const PluginLauncher& plugin;
  std::string twinray = "twinray";  // how reproduce lines start the program (the running executable's path)
  bool images = false;               // render disagreement images (CheckVerdict::image)
  double time_scale = 1.0;           // --time-scale, repeated in reproduce lines when it is not 1
};

struct CheckContext {
  const CheckSpec& spec;
  GradeScene& scene;
  const CheckEnvironment& env;
  std::chrono::steady_clock::time_point deadline;
  // Builds of this plugin that failed in earlier checks (failed_builds.h); none remembered when null.
  FailedBuilds* failed_builds = nullptr;
  // False when the deadline is the suite's time_budget running out before the check's own time_limit.
  bool own_deadline = true;
  mutable int builds = 0;  // plugin builds started by this check

  LaunchLimits limits() const { return {deadline, spec.memory_limit_bytes, spec.ray_time_limit_seconds}; }
  // A fresh plugin instance, built on the check's scene. Throws RecalledBuildFailure instead when the same
  // build failed in an earlier check under limits no more generous (failed_builds.h); `build_seconds`, when
  // given, receives the wall-clock time of the build call.
  std::unique_ptr<Backend> built_plugin(double* build_seconds = nullptr) const;
  // The built-in backend the check's answers are compared with.
  std::string reference_name() const;
  // `twinray trace SCENE --backends plugin:PATH,REFERENCE --ray '...'`: replays one ray.
  std::string trace_command(const Ray& ray) const;
  // `twinray grade PLUGIN --suite SUITE --check NAME`: reruns the whole check.
  std::string grade_command() const;
  // The check's ray count ("count"), or `fallback` when the suite gives none.
  std::size_t count_or(std::size_t fallback) const { return spec.count != 0 ? spec.count : fallback; }
  // `count` rays of each of the check's kinds ("rays", or `fallback` when the suite gives none).
  std::vector<Ray> rays_of_kinds(const std::vector<crosscheck::RayKind>& fallback, std::size_t count) const;
};

struct CheckVerdict {
  bool passed = false;
  bool scored = true;  // false: measured only (a performance check without thresholds): worth no points
  std::string detail;
  std::string reproduce;
  std::optional<Image> image;  // a disagreement image, written by the caller once the run is complete
  nlohmann::json figures = nlohmann::json::object();
};

CheckVerdict run_check(CheckContext& context);

// The families, one file each.
CheckVerdict run_build_check(CheckContext& context);
CheckVerdict run_answer_check(CheckContext& context);  // closest-hit, any-hit, ray-interval, axis-aligned, spheres, ties
CheckVerdict run_watertight_check(CheckContext& context);
CheckVerdict run_thread_safety_check(CheckContext& context);
CheckVerdict run_determinism_check(CheckContext& context);
CheckVerdict run_performance_check(CheckContext& context);
CheckVerdict run_tree_quality_check(CheckContext& context);

// `twinray grade PLUGIN --suite SUITE --check NAME` for any check of the suite.
std::string grade_command(const CheckEnvironment& env, const CheckSpec& spec);

// A word for the shell: as it is when safe, else single-quoted.
std::string shell_quote(const std::string& word);

}  // namespace twinray::grade
