#include "harness/grade/plugin_launcher.h"

#include "backends/plugin/isolated_plugin_backend.h"
#include "backends/plugin/plugin_failure.h"
#include "core/util/input_error.h"

#include <fmt/core.h>

namespace twinray::grade {

namespace {

// The limits of one check: its deadline bounds all work, build included; one ray has its own, shorter limit.
PluginLimits limits_of(const LaunchLimits& l) {
  PluginLimits limits;
  limits.deadline = l.deadline;
  if (l.memory_bytes != 0) limits.memory_bytes = l.memory_bytes;
  if (l.ray_seconds > 0.0) limits.query_seconds = l.ray_seconds;
  return limits;
}

// One line: what happened and where, in the isolated backend's own words (plugin_failure.h). The ray goes
// into the reproduce line and the plugin's output into the check's figures, so both are left out here.
std::string describe_failure(const PluginFailure& f, const std::string& deadline = kCheckDeadline) {
  PluginFailureDetails d = f;
  d.plugin = "the plugin";
  // In a check, the deadline is the check's own time limit (or the suite's budget): say which.
  if (d.deadline_passed) d.detail = deadline;
  d.ray.reset();
  d.ray_index.reset();
  return describe(d);
}

}  // namespace

PluginLauncher::PluginLauncher(std::filesystem::path so) : path_(std::filesystem::absolute(so)) {
  // One worker loads it now: a library that is not a plugin is bad input before any check runs.
  try {
    const std::unique_ptr<IsolatedPluginBackend> probe = make_isolated_plugin_backend(path_);
    name_ = std::string(probe->name());
    traits_ = probe->traits();
    intersect_batch_ = probe->has_intersect_batch();
    occluded_batch_ = probe->has_occluded_batch();
  } catch (const PluginFailure& f) {
    // Dying while loading (a crashing static constructor or create()) is the plugin's failure, but there is
    // nothing to grade: every check would fail the same way.
    throw InputError(path_, "", "the plugin failed while loading: " + describe_failure(f));
  }
}

std::unique_ptr<IsolatedPluginBackend> PluginLauncher::launch(const LaunchLimits& limits) const {
  std::unique_ptr<IsolatedPluginBackend> backend = make_isolated_plugin_backend(path_, limits_of(limits));
  backend->set_batch_path(BatchPath::SingleCalls);
  return backend;
}

FailureReport classify_failure(const std::exception_ptr& failure, double ray_seconds, const std::string& deadline) {
  try {
    std::rethrow_exception(failure);
  } catch (const InputError&) {
    throw;
  } catch (const PluginFailure& f) {
    FailureReport r;
    r.outcome = f.kind == PluginFailureKind::Timeout ? Outcome::Timeout
                : f.kind == PluginFailureKind::Crash ? Outcome::Crash
                                                      : Outcome::Fail;
    r.detail = describe_failure(f, deadline);
    // A ray replays a crash, or a call that never ends. When the check's time runs out, the ray in flight is
    // blamed only if it had been in the plugin for half the limit of one ray: otherwise it merely came last,
    // replaying it alone reproduces nothing, and the check's `grade --check` line is what reproduces it.
    if (!f.deadline_passed || f.call_seconds >= 0.5 * ray_seconds) r.ray = f.ray;
    r.output = f.output;
    return r;
  } catch (const std::runtime_error& e) {
    // What the plugin reported itself (a failed build, with its message) and contract violations the
    // backend found without the worker dying.
    return {Outcome::Fail, e.what(), std::nullopt, {}};
  }
}

}  // namespace twinray::grade
