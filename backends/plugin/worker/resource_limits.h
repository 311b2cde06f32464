#pragma once
// The worker's resource limits, set before any plugin code runs (hard limits too, so the plugin cannot raise
// them; the seccomp filter also refuses setrlimit/prlimit64 with a new limit):
//   RLIMIT_AS      PluginLimits::memory_bytes. Under AddressSanitizer, whose shadow memory reserves terabytes
//                  of address space before main(), the limit is the address space in use at start plus
//                  memory_bytes (twinray also sets ASan's soft_rss_limit_mb, isolated_plugin_backend.cpp).
//   RLIMIT_CORE    0: a crashing plugin leaves no core file behind.
//   RLIMIT_NOFILE  64: the worker holds five descriptors; loading needs a few more for a moment.
// RLIMIT_NPROC is not set: it counts every process of the user, not the worker's, and the seccomp filter
// already forbids creating processes.

#include <cstdint>
#include <string>

namespace twinray::plugin_worker {

// Returns a description of what was set ("RLIMIT_AS 4096 MiB, ..."), or throws std::runtime_error.
std::string apply_resource_limits(std::uint64_t memory_bytes);

}  // namespace twinray::plugin_worker
