#pragma once
// Tracing a ray set through a backend, on one thread or on all of them, the way the benchmarks time it:
// one single-ray call per ray (the calls the renderer makes), FTZ/DAZ on every thread that queries.

#include "bench/bench_scenes.h"

#include <cstddef>
#include <span>
#include <vector>

namespace twinray::bench {

// Traces every ray once; returns the number of hits (kept so the compiler cannot drop the work).
// threads == 1 runs on the calling thread; otherwise a TBB parallel loop over blocks of rays.
std::size_t trace_all(const Backend& backend, std::span<const Ray> rays, QueryKind query, int threads);

// Rays per second of `backend` on `rays`, timed over whole passes until at least `min_seconds` passed.
double measure_rays_per_second(const Backend& backend, std::span<const Ray> rays, QueryKind query, int threads,
                               double min_seconds);

// Per-ray traversal cost of a counting backend: mean and 99th percentile of nodes visited and of
// primitives tested per ray (single thread, each ray with its own QueryStats).
struct PerRayCost {
  double nodes_mean = 0.0, nodes_p99 = 0.0;
  double prims_mean = 0.0, prims_p99 = 0.0;
};
PerRayCost per_ray_cost(const Backend& backend, std::span<const Ray> rays, QueryKind query);

// The value below which `p` (0..1) of the sorted values lie (nearest rank). 0 for no values.
double percentile(std::vector<double> values, double p);

}  // namespace twinray::bench
