#include "harness/report/bench_results.h"

#include "core/util/input_error.h"

#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>

namespace twinray::report {

namespace {

std::vector<std::string> split_name(const std::string& name) {
  std::vector<std::string> parts;
  std::stringstream ss(name);
  std::string part;
  while (std::getline(ss, part, '/'))
    if (part != "manual_time" && part != "real_time" && !part.empty()) parts.push_back(part);
  return parts;
}

double counter(const nlohmann::json& b, const char* key) {
  const auto it = b.find(key);
  return it != b.end() && it->is_number() ? it->get<double>() : 0.0;
}

std::string text_of(const nlohmann::json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

}  // namespace

std::vector<std::string> BenchResults::scenes() const {
  std::vector<std::string> out;
  auto add = [&](const std::string& s) {
    if (std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
  };
  for (const BuildRow& r : builds) add(r.scene);
  for (const TraceRow& r : traces) add(r.scene);
  return out;
}

std::vector<std::string> BenchResults::backends() const {
  std::vector<std::string> out;
  auto add = [&](const std::string& s) {
    if (std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
  };
  for (const BuildRow& r : builds) add(r.backend);
  for (const TraceRow& r : traces) add(r.backend);
  return out;
}

std::optional<BuildRow> BenchResults::build(const std::string& scene, const std::string& backend) const {
  for (const BuildRow& r : builds)
    if (r.scene == scene && r.backend == backend) return r;
  return std::nullopt;
}

std::optional<TraceRow> BenchResults::trace(const std::string& scene, const std::string& backend,
                                            const std::string& kind, const std::string& query, int threads) const {
  for (const TraceRow& r : traces)
    if (r.scene == scene && r.backend == backend && r.kind == kind && r.query == query && r.threads == threads) return r;
  return std::nullopt;
}

BenchResults parse_bench_results(const nlohmann::json& j, const std::filesystem::path& source) {
  if (!j.is_object() || !j.contains("benchmarks") || !j["benchmarks"].is_array())
    throw InputError(source, "", "not a Google Benchmark JSON file (no 'benchmarks' array)");
  BenchResults results;
  if (j.contains("context") && j["context"].is_object())
    for (const auto& [key, value] : j["context"].items())
      if (!value.is_array() && !value.is_object()) results.context[key] = text_of(value);
  if (j.contains("context") && j["context"].contains("caches") && j["context"]["caches"].is_array()) {
    std::string caches;
    for (const auto& c : j["context"]["caches"])
      caches += (caches.empty() ? "" : ", ") + std::string("L") + text_of(c.value("level", nlohmann::json(0))) + " " +
                text_of(c.value("type", nlohmann::json(""))) + " " +
                std::to_string(c.value("size", 0) / 1024) + " KiB";
    results.context["caches"] = caches;
  }

  // Names that have a "median" aggregate use it; the others use their (single) iteration row.
  std::set<std::string> with_median;
  for (const auto& b : j["benchmarks"])
    if (b.value("run_type", "") == "aggregate" && b.value("aggregate_name", "") == "median")
      with_median.insert(b.value("run_name", ""));

  for (const auto& b : j["benchmarks"]) {
    if (!b.is_object() || !b.contains("name")) throw InputError(source, "/benchmarks", "a benchmark without a name");
    const std::string run_name = b.value("run_name", b.value("name", ""));
    const bool aggregate = b.value("run_type", "") == "aggregate";
    if (aggregate && b.value("aggregate_name", "") != "median") continue;
    if (!aggregate && with_median.count(run_name)) continue;
    if (b.contains("error_occurred") && b["error_occurred"].is_boolean() && b["error_occurred"].get<bool>()) continue;
    const std::vector<std::string> parts = split_name(run_name);
    if (parts.size() == 3 && parts[0] == "build") {
      BuildRow r;
      r.scene = parts[1];
      r.backend = parts[2];
      r.family = b.value("label", "");
      r.triangles = counter(b, "triangles");
      r.build_ms = counter(b, "build_ms");
      r.mprims_per_s = counter(b, "Mprims_per_s");
      r.speed_vs_ref = counter(b, "speed_vs_embree_fast");
      r.memory_bytes = counter(b, "memory_bytes");
      r.bytes_per_prim = counter(b, "bytes_per_prim");
      r.nodes = counter(b, "nodes");
      r.leaves = counter(b, "leaves");
      r.depth = counter(b, "depth");
      r.sah_cost = counter(b, "sah_cost");
      results.builds.push_back(r);
    } else if (parts.size() == 6 && parts[0] == "trace" && parts[5].rfind("threads:", 0) == 0) {
      TraceRow r;
      r.scene = parts[1];
      r.backend = parts[2];
      r.kind = parts[3];
      r.query = parts[4];
      r.threads = std::stoi(parts[5].substr(8));
      r.family = b.value("label", "");
      r.triangles = counter(b, "triangles");
      r.mrays_per_s = counter(b, "Mrays_per_s");
      r.speed_vs_ref = counter(b, "speed_vs_embree_fast");
      r.hit_fraction = counter(b, "hit_fraction");
      r.has_cost = b.contains("nodes_per_ray");
      r.nodes_per_ray = counter(b, "nodes_per_ray");
      r.nodes_p99 = counter(b, "nodes_per_ray_p99");
      r.prims_per_ray = counter(b, "prims_per_ray");
      r.prims_p99 = counter(b, "prims_per_ray_p99");
      results.traces.push_back(r);
    }
    // Anything else (other benchmarks in the same file) is ignored.
  }
  return results;
}

BenchResults load_bench_results(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "cannot open the benchmark file");
  nlohmann::json j;
  try {
    in >> j;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, "", std::string("invalid JSON: ") + e.what());
  }
  return parse_bench_results(j, path);
}

}  // namespace twinray::report
