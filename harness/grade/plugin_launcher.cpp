#include "harness/grade/plugin_launcher.h"

#include "backends/plugin/isolated_plugin_backend.h"
#include "backends/plugin/plugin_failure.h"
#include "core/util/input_error.h"

#include <fmt/core.h>

namespace twinray::grade {

namespace {

// The limits of one check: its deadline bounds every call, build included. The per-call limits stay at the
// isolated backend's defaults (PluginLimits), far above any check's time limit, so the deadline decides.
PluginLimits limits_of(const LaunchLimits& l) {
  PluginLimits limits;
  limits.deadline = l.deadline;
  if (l.memory_bytes != 0) limits.memory_bytes = l.memory_bytes;
  return limits;
}

std::string stage_words(const std::string& stage) {
  return stage.empty() ? std::string() : " in " + stage;
}

// One line: what happened and where. The ray goes into the reproduce line, the plugin's output into the
// check's figures.
std::string describe_failure(const PluginFailure& f) {
  const std::string where = stage_words(f.stage);
  const std::string extra = f.detail.empty() ? "" : " (" + f.detail + ")";
  if (f.kind == PluginFailureKind::Timeout) return "no answer within the time limit" + where + extra;
  if (f.cause == "signal") return fmt::format("crashed with {}{}", f.signal_name, where);
  if (f.cause == "abort")
    return fmt::format("aborted ({}){}{}", f.signal_name.empty() ? "SIGABRT" : f.signal_name, where, extra);
  if (f.cause == "exit") return fmt::format("called exit({}){}", f.exit_code, where);
  if (f.cause == "out-of-memory") return "ran out of memory" + where + extra;
  if (f.cause == "sandbox")
    return fmt::format("stopped by the sandbox: system call {}{}", f.syscall.empty() ? "?" : f.syscall, where);
  if (f.cause == "exception") return "let a C++ exception escape" + where + extra;
  if (f.cause == "bad-hit") return "reported a hit on a primitive that does not exist" + where + extra;
  if (f.cause == "load") return "died while loading" + extra;
  return std::string(f.what());
}

}  // namespace

PluginLauncher::PluginLauncher(std::filesystem::path so) : path_(std::filesystem::absolute(so)) {
  // One worker loads it now: a library that is not a plugin is bad input before any check runs.
  try {
    const std::unique_ptr<IsolatedPluginBackend> probe = make_isolated_plugin_backend(path_);
    name_ = std::string(probe->name());
    traits_ = probe->traits();
  } catch (const PluginFailure& f) {
    // Dying while loading (a crashing static constructor or create()) is the plugin's failure, but there is
    // nothing to grade: every check would fail the same way.
    throw InputError(path_, "", "the plugin failed while loading: " + describe_failure(f));
  }
}

std::unique_ptr<Backend> PluginLauncher::launch(const LaunchLimits& limits) const {
  return make_isolated_plugin_backend(path_, limits_of(limits));
}

FailureReport classify_failure(const std::exception_ptr& failure) {
  try {
    std::rethrow_exception(failure);
  } catch (const InputError&) {
    throw;
  } catch (const PluginFailure& f) {
    FailureReport r;
    r.outcome = f.kind == PluginFailureKind::Timeout ? Outcome::Timeout
                : f.kind == PluginFailureKind::Crash ? Outcome::Crash
                                                      : Outcome::Fail;
    r.detail = describe_failure(f);
    r.ray = f.ray;
    r.output = f.output;
    return r;
  } catch (const std::runtime_error& e) {
    // What the plugin reported itself (a failed build, with its message) and contract violations the
    // backend found without the worker dying.
    return {Outcome::Fail, e.what(), std::nullopt, {}};
  }
}

}  // namespace twinray::grade
