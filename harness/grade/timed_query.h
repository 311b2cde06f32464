#pragma once
// Timing a backend's answers for the measuring checks (performance, complexity): one call over all the rays,
// closest hits or any-hit answers, wall clock, with the backend's own traversal counts.

#include "core/backend/backend.h"

#include <cstddef>
#include <cstdint>
#include <span>

namespace twinray::grade {

// Seconds one `intersect` (any_hit false) or `occluded` call over `rays` takes; `stats` gets that call's counts.
double time_one_run(const Backend& backend, std::span<const Ray> rays, bool any_hit, QueryStats& stats);

// A total (seconds, or nodes or primitives counted) per ray; 0 for no rays.
inline double per_ray(double total, std::size_t rays) { return rays ? total / static_cast<double>(rays) : 0.0; }
inline double per_ray(std::uint64_t total, std::size_t rays) { return per_ray(static_cast<double>(total), rays); }

}  // namespace twinray::grade
