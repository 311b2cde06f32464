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

struct CheckContext;
struct CheckVerdict;

// One built instance of the plugin, in its own worker, for one check. Ending it ends the worker the way a
// program that uses the BVH ends: destroy(), then the plugin's atexit handlers and static destructors
// (IsolatedPluginBackend::shutdown). A crash or hang there, or a crash of a plugin thread after the last
// answer, becomes the check's teardown failure (CheckContext::teardown). Checks end an instance as soon as
// they have its answers, so that nothing the plugin left running (a spinning helper thread) runs while the
// grader computes references, times them or judges. The destructor ends it too.
class PluginInstance {
 public:
  PluginInstance(std::unique_ptr<IsolatedPluginBackend> backend, const CheckContext& ctx)
      : backend_(std::move(backend)), ctx_(&ctx) {}
  PluginInstance(PluginInstance&&) = default;
  PluginInstance& operator=(PluginInstance&&) = delete;
  ~PluginInstance() { end(); }

  const Backend& operator*() const { return *backend_; }
  const IsolatedPluginBackend* operator->() const { return backend_.get(); }
  // Which of the worker's instances the following calls go to (IsolatedPluginBackend::use_instance).
  void use_instance(std::size_t index) { backend_->use_instance(index); }
  // Batch queries call the plugin's batch functions from now on (the batch-calls check; launched instances
  // call its single-ray functions, PluginLauncher::launch).
  void use_batch_functions() { backend_->set_batch_path(BatchPath::PluginBatch); }
  // Back to the single-ray functions (the performance check times both paths).
  void use_single_calls() { backend_->set_batch_path(BatchPath::SingleCalls); }
  // Ends the worker; afterwards the instance answers nothing. Never throws.
  void end();

 private:
  std::unique_ptr<IsolatedPluginBackend> backend_;
  const CheckContext* ctx_;
};

struct CheckContext {
  const CheckSpec& spec;
  GradeScene& scene;
  const CheckEnvironment& env;
  std::chrono::steady_clock::time_point deadline;
  // Builds of this plugin that failed in earlier checks (failed_builds.h); none remembered when null.
  FailedBuilds* failed_builds = nullptr;
  // The scene of the check's second instance (CheckSpec::second_scene), loaded; null when it has none.
  GradeScene* second_scene = nullptr;
  // False when the deadline is the suite's time_budget running out before the check's own time_limit.
  bool own_deadline = true;
  mutable int builds = 0;  // plugin builds started by this check
  // The first failure of a plugin instance at its end (PluginInstance), if one had any: a PluginFailure.
  mutable std::exception_ptr teardown = nullptr;

  LaunchLimits limits() const { return {deadline, spec.memory_limit_bytes, spec.ray_time_limit_seconds}; }
  // A fresh plugin instance, built on the check's scene. Throws RecalledBuildFailure instead when the same
  // build failed in an earlier check under limits no more generous (failed_builds.h); `build_seconds`, when
  // given, receives the wall-clock time of the build call.
  PluginInstance built_plugin(double* build_seconds = nullptr) const;
  // The plugin's answers to `ray` asked alone, of a fresh instance built on the check's scene, the way the
  // reproduce line's `twinray trace` asks them (closest hit, then any hit); nullopt when that replay fails
  // (crashes, times out: within the check's own deadline) or cannot be made. A failure no single ray replays
  // (an answer that depends on the rays asked before, memory that ran out over many calls) is reproduced by
  // rerunning the check instead.
  struct AloneAnswer {
    Hit hit;
    bool occluded = false;
  };
  std::optional<AloneAnswer> answer_alone(const Ray& ray) const;
  // For a check that failed on a wrong answer, whose reproduce line traces `ray`: asks the ray alone
  // (answer_alone) and, when the plugin then answers otherwise than it did among the check's rays (its
  // `batch_hit`, or `batch_occluded` for an any-hit answer), says so in the detail and reruns the check as the
  // reproduce line. Figure `replays_alone` records whether the ray alone gives the same answer.
  void confirm_replay(CheckVerdict& v, const Ray& ray, bool any_hit, const Hit& batch_hit, bool batch_occluded) const;
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
CheckVerdict run_batch_check(CheckContext& context);  // batch-calls
CheckVerdict run_complexity_check(CheckContext& context);

// `twinray grade PLUGIN --suite SUITE --check NAME` for any check of the suite.
std::string grade_command(const CheckEnvironment& env, const CheckSpec& spec);

// A word for the shell: as it is when safe, else single-quoted.
std::string shell_quote(const std::string& word);

}  // namespace twinray::grade
