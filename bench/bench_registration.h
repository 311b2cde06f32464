#pragma once
// The benchmark bodies bench_main.cpp registers, one call per (scene, backend, ...) case.
//
// Benchmark names (parsed by `twinray report`, harness/report/bench_results.h):
//   build/SCENE/BACKEND[/manual_time]
//   trace/SCENE/BACKEND/KIND/QUERY/threads:N[/real_time]
// Counters are documented in docs/benchmarks.md.

#include "bench/bench_scenes.h"

#include <benchmark/benchmark.h>

#include <string>

namespace twinray::bench {

struct TraceCase {
  BenchSceneSpec scene;
  std::string backend;
  BenchRayKind kind = BenchRayKind::Primary;
  QueryKind query = QueryKind::Closest;
  int threads = 1;
};

void run_build_benchmark(benchmark::State& state, const BenchSceneSpec& spec, const std::string& backend_name);
void run_trace_benchmark(benchmark::State& state, const TraceCase& c);

}  // namespace twinray::bench
