#pragma once
// What an isolated plugin (isolated_plugin_backend.h) may spend: time per call, time for everything, memory,
// and how much of what it prints is kept. Exceeding a time limit ends the worker and is reported as a
// PluginFailure of kind Timeout; exceeding the memory limit makes the plugin's allocations fail, which the
// worker reports as cause "out-of-memory" (docs/plugin-abi.md, "Isolation and sandbox").

#include <chrono>
#include <cstddef>
#include <optional>

namespace twinray {

struct PluginLimits {
  // One plugin call (one ray; build_stats; destroy) longer than this is a Timeout. Ten seconds is four orders
  // of magnitude above a brute-force query over a 100k-triangle scene, so only a plugin that hangs reaches it.
  double query_seconds = 10.0;
  // Loading the library plus create(), and build() (each on its own): the reference builders take about a
  // second per million triangles on one core, so five minutes leaves room for slow but finishing builders.
  double build_seconds = 300.0;
  // Wall clock for all work of this instance (e.g. `twinray grade`'s per-check limit); none when empty.
  // May be changed between calls with IsolatedPluginBackend::set_deadline.
  std::optional<std::chrono::steady_clock::time_point> deadline;
  // The worker's address space (RLIMIT_AS): the plugin's tree, the scene it shares with twinray, the worker's
  // 16 query threads' stacks (8 MiB each) and the C/C++ runtime. 4 GiB holds a BVH of tens of millions of
  // triangles and stops a runaway allocation long before it hurts a machine with 8 GiB or more. Under
  // AddressSanitizer, whose shadow memory reserves terabytes of address space, the limit is applied as
  // ASan's own malloc limit instead (docs/plugin-abi.md).
  std::size_t memory_bytes = std::size_t{4} << 30;
  // Captured stdout + stderr kept: the first and the last half of it when the plugin prints more.
  std::size_t output_bytes = 64 * 1024;
};

}  // namespace twinray
