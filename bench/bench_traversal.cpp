// Traversal benchmarks: closest-hit and any-hit throughput for one ray set, on one thread or all, with
// the ratio to embree-fast on the same rays and, for backends that count traversal, the per-ray cost.

#include "bench/bench_registration.h"

#include "bench/bench_tracing.h"

#include <fmt/core.h>

#include <chrono>
#include <map>

namespace twinray::bench {

namespace {

// Per-ray costs are deterministic: computed once per (scene, backend, rays, query), not on every one of
// the calls Google Benchmark makes while it settles the iteration count.
const PerRayCost& cached_per_ray_cost(const std::string& key, const Backend& backend, std::span<const Ray> rays,
                                      QueryKind query) {
  static std::map<std::string, PerRayCost> cache;
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, per_ray_cost(backend, rays, query)).first;
  return it->second;
}

}  // namespace

void run_trace_benchmark(benchmark::State& state, const TraceCase& c) {
  const std::vector<Ray>& rays = rays_for(c.scene, c.kind);
  const Backend& backend = backend_for(c.scene, c.backend);
  const std::string reference_key =
      fmt::format("trace|{}|{}|{}|{}", c.scene.name, to_string(c.kind), to_string(c.query), c.threads);

  std::size_t hits = 0;
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    hits = trace_all(backend, rays, c.query, c.threads);
    benchmark::DoNotOptimize(hits);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double rays_per_second = static_cast<double>(rays.size()) * static_cast<double>(state.iterations()) / seconds;

  if (c.backend == kReferenceBackend) store_reference_rate(reference_key, rays_per_second);
  std::optional<double> reference = reference_rate(reference_key);
  if (!reference) {
    // embree-fast was filtered out of this run: measure it now on the same rays.
    reference = measure_rays_per_second(backend_for(c.scene, kReferenceBackend), rays, c.query, c.threads, 0.2);
    store_reference_rate(reference_key, *reference);
  }

  state.counters["rays"] = static_cast<double>(rays.size());
  state.counters["hit_fraction"] = rays.empty() ? 0.0 : static_cast<double>(hits) / static_cast<double>(rays.size());
  state.counters["threads"] = static_cast<double>(c.threads);
  state.counters["Mrays_per_s"] = rays_per_second * 1e-6;
  // > 1: faster than embree-fast on the same rays in the same run.
  state.counters["speed_vs_embree_fast"] = rays_per_second / *reference;
  if (backend.traits().counts_traversal) {
    const std::string cost_key = fmt::format("{}|{}|{}|{}", c.scene.name, c.backend, to_string(c.kind), to_string(c.query));
    const PerRayCost& cost = cached_per_ray_cost(cost_key, backend, rays, c.query);
    state.counters["nodes_per_ray"] = cost.nodes_mean;
    state.counters["nodes_per_ray_p99"] = cost.nodes_p99;
    state.counters["prims_per_ray"] = cost.prims_mean;
    state.counters["prims_per_ray_p99"] = cost.prims_p99;
  }
  state.counters["triangles"] = static_cast<double>(scene_for(c.scene).geometry.triangle_count());
  state.SetLabel(c.scene.family);
}

}  // namespace twinray::bench
