#include "harness/grade/failed_builds.h"

#include "backends/plugin/plugin_failure.h"

#include <fmt/core.h>

namespace twinray::grade {

std::optional<FailedBuild> FailedBuilds::recall(const CheckSpec& spec) const {
  const auto it = by_scene_and_memory_.find({spec.scene, spec.memory_limit_bytes});
  if (it == by_scene_and_memory_.end()) return std::nullopt;
  const FailedBuild& f = it->second;
  const bool same = f.failure.outcome == Outcome::Timeout ? spec.time_limit_seconds <= f.time_limit_seconds
                                                          : spec.time_limit_seconds >= f.seconds;
  if (!same) return std::nullopt;
  return f;
}

void FailedBuilds::remember(const CheckSpec& spec, const std::exception_ptr& failure, double seconds, bool own_deadline) {
  try {
    std::rethrow_exception(failure);
  } catch (const PluginFailure& p) {
    if (p.stage != "build") return;
    if (p.kind == PluginFailureKind::Timeout && p.deadline_passed && !own_deadline) return;
    if (p.kind != PluginFailureKind::Timeout && p.kind != PluginFailureKind::Crash) return;
    FailedBuild f{spec.name, classify_failure(failure, spec.ray_time_limit_seconds), spec.time_limit_seconds, seconds};
    f.failure.ray.reset();
    // The earliest failure stays: it is the one a reader can rerun (its check's reproduce line).
    by_scene_and_memory_.try_emplace({spec.scene, spec.memory_limit_bytes}, std::move(f));
  } catch (...) {
    // Not a plugin failure (a declined build is quick to repeat; anything else is not the plugin's).
  }
}

std::string FailedBuilds::recalled_detail(const FailedBuild& f) {
  const std::string what = f.failure.outcome == Outcome::Timeout ? "timed out" : "crashed";
  return fmt::format("build {} in check '{}' (same scene and memory limit, time_limit {:g} s); not built again: {}", what,
                     f.check, f.time_limit_seconds, f.failure.detail);
}

}  // namespace twinray::grade
