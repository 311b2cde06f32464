#pragma once
// The rows of a twinray_bench Google Benchmark JSON file, by meaning.
//
// Benchmark names (bench/bench_registration.h):
//   build/SCENE/BACKEND[/manual_time]
//   trace/SCENE/BACKEND/KIND/QUERY/threads:N[/real_time]
// With --benchmark_repetitions, the "median" aggregate rows are used instead of the single runs.

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace twinray::report {

struct BuildRow {
  std::string scene, family, backend;
  double triangles = 0, build_ms = 0, mprims_per_s = 0, speed_vs_ref = 0, memory_bytes = 0, bytes_per_prim = 0;
  double nodes = 0, leaves = 0, depth = 0, sah_cost = 0;  // 0 when the backend has no accessible tree
};

struct TraceRow {
  std::string scene, family, backend, kind, query;
  int threads = 1;
  double triangles = 0, mrays_per_s = 0, speed_vs_ref = 0, hit_fraction = 0;
  bool has_cost = false;  // the per-ray figures below are present
  double nodes_per_ray = 0, nodes_p99 = 0, prims_per_ray = 0, prims_p99 = 0;
};

struct BenchResults {
  std::vector<BuildRow> builds;
  std::vector<TraceRow> traces;
  std::map<std::string, std::string> context;  // Google Benchmark's context, flattened to text

  std::vector<std::string> scenes() const;   // in first-seen order
  std::vector<std::string> backends() const; // in first-seen order
  std::optional<BuildRow> build(const std::string& scene, const std::string& backend) const;
  std::optional<TraceRow> trace(const std::string& scene, const std::string& backend, const std::string& kind,
                                const std::string& query, int threads) const;
};

// Throws InputError naming `source` for JSON that is not a Google Benchmark output.
BenchResults parse_bench_results(const nlohmann::json& j, const std::filesystem::path& source);
BenchResults load_bench_results(const std::filesystem::path& path);

}  // namespace twinray::report
