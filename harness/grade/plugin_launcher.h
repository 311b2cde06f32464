#pragma once
// The plugin under test, started afresh for every check: its own worker process with the check's limits
// (backends/plugin: the parent never runs plugin code), so a crash, a hang or a corrupted heap in one check
// cannot touch the next one or the grader.
//
// classify_failure turns what a plugin backend throws into a check outcome: crash (a signal, abort, exit,
// out of memory or a sandbox violation), timeout, or fail (a contract violation: a hit on a primitive that
// does not exist, a failed build), with a one-line detail and the ray being traced when it happened.

#include "backends/plugin/isolated_plugin_backend.h"
#include "core/backend/backend.h"
#include "harness/grade/vocabulary.h"

#include <chrono>
#include <exception>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace twinray::grade {

struct LaunchLimits {
  std::chrono::steady_clock::time_point deadline;  // the end of the check's wall-clock budget
  std::size_t memory_bytes = 0;                    // 0: the backend's default
  double ray_seconds = 0.0;                        // one call into the plugin (one ray); 0: the backend's default
};

class PluginLauncher {
 public:
  // Loads the plugin once, in a worker, to check it (InputError for a missing file, a library that is not a
  // plugin, a wrong ABI version, a plugin that dies while loading) and to read its name and claims.
  explicit PluginLauncher(std::filesystem::path so);

  // A fresh, unbuilt instance in a new worker process, with the check's deadline and memory limit. Its batch
  // queries call the plugin's single-ray functions (BatchPath::SingleCalls): every check but batch-calls judges
  // intersect1 / occluded1, the functions every plugin has (docs/grading.md, "batch-calls").
  std::unique_ptr<IsolatedPluginBackend> launch(const LaunchLimits& limits) const;

  const std::filesystem::path& path() const { return path_; }  // absolute
  const std::string& name() const { return name_; }            // "plugin:NAME"
  const BackendTraits& traits() const { return traits_; }
  // The optional batch entry points the plugin's table has (the batch-calls check's applicability).
  bool has_intersect_batch() const { return intersect_batch_; }
  bool has_occluded_batch() const { return occluded_batch_; }

 private:
  std::filesystem::path path_;
  std::string name_;
  BackendTraits traits_;
  bool intersect_batch_ = false, occluded_batch_ = false;
};

struct FailureReport {
  Outcome outcome = Outcome::Fail;  // crash, timeout or fail
  std::string detail;               // one line
  std::optional<Ray> ray;           // the ray being traced, when known
  std::string output;               // what the plugin printed (captured by its worker, truncated)
};

// What the exception a plugin call threw means for the check. Rethrows what is not a plugin failure (bad
// input, a grader bug) so it is never mistaken for the student's fault.
// `ray_seconds` is the check's limit for one ray (ray_time_limit); `deadline` says, in words, what the
// deadline of a timeout that ran into it was.
inline constexpr const char* kCheckDeadline = "the check's time_limit, build included, ran out";
FailureReport classify_failure(const std::exception_ptr& failure, double ray_seconds,
                               const std::string& deadline = kCheckDeadline);

}  // namespace twinray::grade
