#pragma once
// Timing a backend's answers for the measuring checks (performance, complexity): one call over all the rays,
// closest hits or any-hit answers, by wall clock and by CPU time, with the backend's own traversal counts.
//
// CPU time (docs/grading.md, "The thirteenth round: CPU time"): what the answering took of a processor, which
// a busy machine moves far less than wall clock (waiting for a core is not counted). For a plugin, the CPU
// time of its worker process around the call, every thread of it (IsolatedPluginBackend::worker_cpu_seconds:
// a plugin that hands work to threads of its own is charged for them; the grader's side of the round trips,
// copying rays and checking answers, is not); for a backend in the grader's process (bvh, embree-fast, whose
// queries run on the calling thread), the calling thread's CPU time (CLOCK_THREAD_CPUTIME_ID).

#include "core/backend/backend.h"

#include <cstddef>
#include <cstdint>
#include <span>

namespace twinray::grade {

struct RunTime {
  double wall = 0.0;  // seconds, steady clock
  double cpu = 0.0;   // seconds of CPU time as above; negative when it could not be read
  bool has_cpu() const { return cpu >= 0.0; }
};

// One `intersect` (any_hit false) or `occluded` call over `rays`, timed; `stats` gets that call's counts.
RunTime time_run(const Backend& backend, std::span<const Ray> rays, bool any_hit, QueryStats& stats);

// A total (seconds, or nodes or primitives counted) per ray; 0 for no rays.
inline double per_ray(double total, std::size_t rays) { return rays ? total / static_cast<double>(rays) : 0.0; }
inline double per_ray(std::uint64_t total, std::size_t rays) { return per_ray(static_cast<double>(total), rays); }

}  // namespace twinray::grade
