#pragma once
// A plugin's build of a scene that ran out of time, crashed or ran out of memory in one check is not run again
// by a later check that would give it no more: the later check reports the same outcome at once, naming the
// check it happened in. Without this a plugin whose build hangs costs every check on that scene its whole
// time limit (minutes for the quick suite, more than half an hour for the default one).
//
// Fair by construction (docs/grading.md, "Isolation and limits"): a failure is recalled only for the same
// scene and the same memory limit, and
//   - a timeout only by a check whose time_limit is no longer than the one the build ran out of (a build that
//     did not end in 20 s is given its 60 s when a later check offers them);
//   - a crash (signal, abort, exit, exception, out of memory, sandbox) only by a check whose time_limit is at
//     least the time the build ran before it crashed (it would get as far).
// Only the first build of a check is remembered: it had the check's whole time_limit (less the grader's own
// milliseconds of starting the worker and making rays), whereas a second build (determinism) had less.
// A build that failed because the suite's time_budget ran out is not remembered either.

#include "harness/grade/plugin_launcher.h"
#include "harness/grade/suite.h"

#include <cstddef>
#include <exception>
#include <map>
#include <optional>
#include <string>
#include <utility>

namespace twinray::grade {

struct FailedBuild {
  std::string check;              // the check it happened in
  FailureReport failure;          // its outcome and one-line detail (the ray is always empty: no ray was traced)
  double time_limit_seconds = 0;  // that check's time_limit
  double seconds = 0;             // how long the build ran before it failed
};

// Thrown by CheckContext::built_plugin instead of building again; the suite runner turns it into the check's
// outcome.
struct RecalledBuildFailure : std::exception {
  explicit RecalledBuildFailure(FailedBuild f) : failed(std::move(f)) {}
  const char* what() const noexcept override { return "a build that failed in an earlier check"; }
  FailedBuild failed;
};

class FailedBuilds {
 public:
  // The failure a build of `spec`'s scene under `spec`'s limits would repeat, if one is remembered.
  std::optional<FailedBuild> recall(const CheckSpec& spec) const;
  // Remembers the failure of a check's first build, when it is one worth remembering (a timeout or a crash
  // in stage "build"). `failure` is what the build threw, `seconds` how long the build ran; `own_deadline`
  // false when the check's deadline was cut short by the suite's time_budget.
  void remember(const CheckSpec& spec, const std::exception_ptr& failure, double seconds, bool own_deadline);

  // The detail of a check that recalls `f` rather than building again.
  static std::string recalled_detail(const FailedBuild& f);

 private:
  std::map<std::pair<std::string, std::size_t>, FailedBuild> by_scene_and_memory_;
};

}  // namespace twinray::grade
