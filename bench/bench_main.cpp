// twinray_bench: build and traversal benchmarks of every backend over the procedural scale series and the
// shared meshes. Google Benchmark flags work as usual (--benchmark_out=FILE --benchmark_out_format=json,
// --benchmark_filter=REGEX, --benchmark_min_time=SECONDS); twinray's own flags come first:
//   --twinray_max_triangles=N        largest scale-series scene (default 4194304 = 4M)
//   --twinray_rays=N                 rays per ray set (default 65536)
//   --twinray_threads=LIST           thread counts for the shared meshes: "1", "all" or "1,all" (default)
//   --twinray_series_threads=LIST    thread counts for the procedural scale series (default "1": the series
//                                    is about scaling with N, and 28 scenes at two thread counts would
//                                    double the run time)
//   --twinray_backends=LIST          default embree-fast,bvh8,bvh,embree,brute (embree-fast always runs first)
//   --twinray_brute_max_triangles=N  brute force only on scenes up to N triangles (default 1024)
//   --twinray_meshes=0               leave out the shared meshes
//   --twinray_scenes=FILE[,FILE...]  also benchmark these scene files (.json, Mitsuba .xml, or a bare .obj /
//                                    .ply mesh), named by their stem; with --twinray_max_triangles=0 and
//                                    --twinray_meshes=0, only them. A file that does not load is an error
//                                    (exit code 2) before anything runs.
// The shared meshes are read from $TWINRAY_SHARED/data/meshes (scenes whose file is missing are left out),
// and with them the interior views scenes/sponza-interior.json, scenes/dragon-closeup.json and
// scenes/cornell-box-reference.json.

#include "bench/bench_registration.h"
#include "core/scene/scene_loader.h"

#include <OpenImageIO/oiioversion.h>
#include <embree3/rtcore_config.h>
#include <fmt/core.h>
#include <oneapi/tbb/version.h>
#include <tbb/info.h>

#include <algorithm>
#include <exception>
#include <filesystem>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace twinray::bench;

struct BenchOptions {
  std::size_t max_triangles = std::size_t{1} << 22;
  std::size_t rays = std::size_t{1} << 16;
  std::vector<int> threads;
  std::vector<int> series_threads;
  std::vector<std::string> backends = {"embree-fast", "bvh8", "bvh", "embree", "brute"};
  std::size_t brute_max_triangles = 1024;
  bool meshes = true;
  std::vector<std::filesystem::path> scenes;
};

std::vector<std::string> split(const std::string& list) {
  std::vector<std::string> items;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) items.push_back(item);
  return items;
}

// Removes --twinray_* flags from argv (Google Benchmark rejects flags it does not know).
BenchOptions take_twinray_flags(int& argc, char** argv) {
  BenchOptions o;
  const int all = static_cast<int>(tbb::info::default_concurrency());
  std::string threads = "1,all", series_threads = "1";
  int kept = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value_of = [&](const std::string& flag) -> std::optional<std::string> {
      const std::string prefix = "--" + flag + "=";
      if (arg.rfind(prefix, 0) == 0) return arg.substr(prefix.size());
      return std::nullopt;
    };
    if (auto v = value_of("twinray_max_triangles")) o.max_triangles = std::stoull(*v);
    else if (auto r = value_of("twinray_rays")) o.rays = std::stoull(*r);
    else if (auto t = value_of("twinray_threads")) threads = *t;
    else if (auto st = value_of("twinray_series_threads")) series_threads = *st;
    else if (auto b = value_of("twinray_backends")) o.backends = split(*b);
    else if (auto m = value_of("twinray_brute_max_triangles")) o.brute_max_triangles = std::stoull(*m);
    else if (auto s = value_of("twinray_meshes")) o.meshes = *s != "0";
    else if (auto f = value_of("twinray_scenes"))
      for (const std::string& path : split(*f)) o.scenes.emplace_back(path);
    else argv[kept++] = argv[i];
  }
  argc = kept;
  for (const std::string& t : split(threads)) o.threads.push_back(t == "all" ? all : std::stoi(t));
  for (const std::string& t : split(series_threads)) o.series_threads.push_back(t == "all" ? all : std::stoi(t));
  // The reference backend runs first for every scene, so its timings are in the cache when the others
  // compute their ratios.
  auto ref = std::find(o.backends.begin(), o.backends.end(), kReferenceBackend);
  if (ref != o.backends.end()) std::rotate(o.backends.begin(), ref, ref + 1);
  return o;
}

std::size_t expected_triangles(const BenchSceneSpec& spec) {
  // Meshes and views: never brute force (the smallest shared mesh has tens of thousands of triangles).
  return spec.family == "mesh" || spec.family == "view" ? static_cast<std::size_t>(-1) : spec.target_triangles;
}

void register_benchmarks(const BenchOptions& o) {
  std::optional<std::filesystem::path> shared;
  if (const char* env = std::getenv("TWINRAY_SHARED"); env && *env && o.meshes) shared = std::filesystem::path(env);
  for (const BenchSceneSpec& spec : scene_specs(o.max_triangles, shared, o.scenes)) {
    std::vector<std::string> backends;
    for (const std::string& b : o.backends)
      if (b != "brute" || expected_triangles(spec) <= o.brute_max_triangles) backends.push_back(b);
    for (const std::string& b : backends)
      benchmark::RegisterBenchmark(fmt::format("build/{}/{}", spec.name, b).c_str(),
                                   [spec, b](benchmark::State& s) { run_build_benchmark(s, spec, b); })
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond);
    for (BenchRayKind kind : kBenchRayKinds)
      for (QueryKind query : {QueryKind::Closest, QueryKind::Any})
        for (int threads : spec.family == "mesh" || spec.family == "view" ? o.threads : o.series_threads)
          for (const std::string& b : backends) {
            const TraceCase c{spec, b, kind, query, threads};
            benchmark::RegisterBenchmark(
                fmt::format("trace/{}/{}/{}/{}/threads:{}", spec.name, b, to_string(kind), to_string(query), threads).c_str(),
                [c](benchmark::State& s) { run_trace_benchmark(s, c); })
                ->UseRealTime()
                ->Unit(benchmark::kMillisecond);
          }
  }
}

// Loads every user scene once before anything is registered, so that a missing or malformed file stops the
// run with the loader's message (which names the file and the place) instead of failing half-way through.
bool user_scenes_load(const BenchOptions& o) {
  for (const std::filesystem::path& path : o.scenes) {
    try {
      const twinray::Scene scene = twinray::load_scene(path);
      if (scene.geometry.triangle_count() + scene.geometry.sphere_count() == 0) {
        fmt::print(stderr, "twinray_bench: {}: the scene has no primitives to trace\n", path.string());
        return false;
      }
    } catch (const std::exception& e) {
      fmt::print(stderr, "twinray_bench: {}\n", e.what());
      return false;
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  BenchOptions options;
  try {
    options = take_twinray_flags(argc, argv);
  } catch (const std::exception& e) {  // std::stoull / std::stoi on a malformed number
    fmt::print(stderr, "twinray_bench: bad --twinray_* value: {}\n", e.what());
    return 2;
  }
  if (!user_scenes_load(options)) return 2;
  set_rays_per_set(options.rays);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;

  benchmark::AddCustomContext("twinray_compiler", fmt::format("{} {}",
#if defined(__clang__)
                                                              "clang",
#else
                                                              "gcc",
#endif
                                                              __VERSION__));
  benchmark::AddCustomContext("twinray_embree", RTC_VERSION_STRING);
  benchmark::AddCustomContext("twinray_tbb", TBB_VERSION_STRING);
  benchmark::AddCustomContext("twinray_openimageio", OIIO_VERSION_STRING);
  benchmark::AddCustomContext("twinray_fmt", std::to_string(FMT_VERSION));
  benchmark::AddCustomContext("twinray_rays_per_set", std::to_string(options.rays));
  benchmark::AddCustomContext("twinray_all_threads", std::to_string(tbb::info::default_concurrency()));
  register_benchmarks(options);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
