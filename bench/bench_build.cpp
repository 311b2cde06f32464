// Build benchmarks: time to build each backend's acceleration structure on each scene (all threads: the
// builders are parallel), with the tree and memory figures of the last build as counters.

#include "bench/bench_registration.h"

#include "backends/registry.h"
#include "core/util/fp_mode.h"

#include <chrono>

namespace twinray::bench {

namespace {

double build_seconds_once(const Scene& scene, const std::string& backend_name) {
  std::unique_ptr<Backend> backend = make_backend(backend_name);
  const ScopedFlushDenormals ftz;
  const auto start = std::chrono::steady_clock::now();
  backend->build(scene.geometry);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

void run_build_benchmark(benchmark::State& state, const BenchSceneSpec& spec, const std::string& backend_name) {
  const Scene& scene = scene_for(spec);
  const auto primitives = static_cast<double>(scene.geometry.primitive_count());
  const std::string reference_key = "build|" + spec.name;

  std::unique_ptr<Backend> last;
  double total_seconds = 0.0;
  for (auto _ : state) {
    // The previous backend is destroyed here, outside the timed region (manual time).
    last = make_backend(backend_name);
    const ScopedFlushDenormals ftz;
    const auto start = std::chrono::steady_clock::now();
    last->build(scene.geometry);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.SetIterationTime(seconds);
    total_seconds += seconds;
  }
  const double mean_seconds = total_seconds / static_cast<double>(state.iterations());
  const double prims_per_second = primitives / mean_seconds;

  if (backend_name == kReferenceBackend) store_reference_rate(reference_key, prims_per_second);
  std::optional<double> reference = reference_rate(reference_key);
  if (!reference) {
    // embree-fast was filtered out of this run: time it once now, on the same geometry.
    reference = primitives / build_seconds_once(scene, kReferenceBackend);
    store_reference_rate(reference_key, *reference);
  }

  const BuildStats stats = last->build_stats();
  state.counters["triangles"] = static_cast<double>(stats.triangles);
  state.counters["build_ms"] = 1e3 * mean_seconds;
  state.counters["Mprims_per_s"] = prims_per_second * 1e-6;
  // > 1: this backend builds faster than embree-fast on the same geometry in the same run.
  state.counters["speed_vs_embree_fast"] = prims_per_second / *reference;
  state.counters["memory_bytes"] = static_cast<double>(stats.memory_bytes);
  state.counters["bytes_per_prim"] = static_cast<double>(stats.memory_bytes) / primitives;
  if (stats.nodes > 0) {
    state.counters["nodes"] = static_cast<double>(stats.nodes);
    state.counters["leaves"] = static_cast<double>(stats.leaves);
    state.counters["depth"] = static_cast<double>(stats.max_depth);
    state.counters["sah_cost"] = stats.sah_cost;
  }
  state.SetLabel(spec.family);
  // Traversal benchmarks of this scene reuse the tree instead of building their own.
  keep_backend(spec, backend_name, std::move(last));
}

}  // namespace twinray::bench
