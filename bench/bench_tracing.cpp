#include "bench/bench_tracing.h"

#include "core/util/fp_mode.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>

namespace twinray::bench {

namespace {

std::size_t trace_range(const Backend& backend, std::span<const Ray> rays, QueryKind query) {
  std::size_t hits = 0;
  if (query == QueryKind::Closest) {
    for (const Ray& r : rays) {
      Hit h;
      hits += backend.intersect(r, h) ? 1u : 0u;
    }
  } else {
    for (const Ray& r : rays) hits += backend.occluded(r) ? 1u : 0u;
  }
  return hits;
}

}  // namespace

std::size_t trace_all(const Backend& backend, std::span<const Ray> rays, QueryKind query, int threads) {
  if (threads == 1) {
    const ScopedFlushDenormals ftz;
    return trace_range(backend, rays, query);
  }
  // Blocks of 1024 rays: large enough that scheduling costs nothing measurable, small enough that two to
  // a few dozen threads stay balanced on 2^16 rays.
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, rays.size(), 1024), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t acc) {
        const ScopedFlushDenormals ftz;
        return acc + trace_range(backend, rays.subspan(r.begin(), r.size()), query);
      },
      std::plus<>());
}

double measure_rays_per_second(const Backend& backend, std::span<const Ray> rays, QueryKind query, int threads,
                               double min_seconds) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  std::size_t traced = 0;
  double elapsed = 0.0;
  do {
    trace_all(backend, rays, query, threads);
    traced += rays.size();
    elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  } while (elapsed < min_seconds);
  return static_cast<double>(traced) / elapsed;
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  const auto rank = static_cast<std::size_t>(std::ceil(p * static_cast<double>(values.size())));
  const std::size_t k = std::min(values.size() - 1, rank == 0 ? 0 : rank - 1);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

PerRayCost per_ray_cost(const Backend& backend, std::span<const Ray> rays, QueryKind query) {
  std::vector<double> nodes, prims;
  nodes.reserve(rays.size());
  prims.reserve(rays.size());
  const ScopedFlushDenormals ftz;
  for (const Ray& r : rays) {
    QueryStats s;
    if (query == QueryKind::Closest) {
      Hit h;
      backend.intersect(r, h, &s);
    } else {
      backend.occluded(r, &s);
    }
    nodes.push_back(static_cast<double>(s.nodes_visited));
    prims.push_back(static_cast<double>(s.primitives_tested));
  }
  PerRayCost c;
  const double n = rays.empty() ? 1.0 : static_cast<double>(rays.size());
  for (double v : nodes) c.nodes_mean += v / n;
  for (double v : prims) c.prims_mean += v / n;
  c.nodes_p99 = percentile(std::move(nodes), 0.99);
  c.prims_p99 = percentile(std::move(prims), 0.99);
  return c;
}

}  // namespace twinray::bench
