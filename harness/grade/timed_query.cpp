#include "harness/grade/timed_query.h"

#include "backends/plugin/isolated_plugin_backend.h"

#include <chrono>
#include <ctime>
#include <optional>
#include <vector>

namespace twinray::grade {

namespace {

std::optional<double> thread_cpu_seconds() {
  timespec ts{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0) return std::nullopt;
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

// The CPU clock that charges `backend`'s work: its worker's for a plugin, this thread's otherwise.
std::optional<double> cpu_seconds(const IsolatedPluginBackend* plugin) {
  return plugin ? plugin->worker_cpu_seconds() : thread_cpu_seconds();
}

}  // namespace

RunTime time_run(const Backend& backend, std::span<const Ray> rays, bool any_hit, QueryStats& stats) {
  const auto* plugin = dynamic_cast<const IsolatedPluginBackend*>(&backend);
  std::vector<Hit> hits(any_hit ? 0 : rays.size());
  std::vector<std::uint8_t> occluded(any_hit ? rays.size() : 0);
  stats = {};
  const std::optional<double> cpu_start = cpu_seconds(plugin);
  const auto start = std::chrono::steady_clock::now();
  if (any_hit) backend.occluded(rays, std::span<std::uint8_t>(occluded), &stats);
  else backend.intersect(rays, std::span<Hit>(hits), &stats);
  RunTime t;
  t.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::optional<double> cpu_end = cpu_seconds(plugin);
  t.cpu = cpu_start && cpu_end ? *cpu_end - *cpu_start : -1.0;
  return t;
}

}  // namespace twinray::grade
