#pragma once
// What the benchmarks run on, and the per-process caches that let every backend see the same scene, the
// same rays and the same embree-fast reference timings.
//
// Benchmarks run in registration order (bench_main.cpp registers, per scene: embree-fast first, then the
// others), so the caches below hold one scene at a time: asking for another scene drops the previous one
// with its backends and rays. That keeps the 4M-triangle scenes of the scale series from piling up.

#include "harness/crosscheck/ray_kinds.h"
#include "core/backend/backend.h"
#include "core/scene/procedural_bench.h"
#include "core/scene/scene.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace twinray::bench {

// The one backend every other is compared with (ratios "vs embree-fast").
inline constexpr const char* kReferenceBackend = "embree-fast";

struct BenchSceneSpec {
  std::string name;                       // "sphere-64k", "bunny", ... (appears in benchmark names)
  std::string family;                     // sphere, soup, terrain, hairball, "mesh" (a bare shared mesh) or
                                          // "view" (a scene file of scenes/ with its own camera and lights)
  std::size_t target_triangles = 0;       // procedural: the requested size
  std::filesystem::path file;             // mesh: the file to load
};

// The three ray kinds the benchmarks trace, and their names in benchmark names and reports.
enum class BenchRayKind { Primary, Shadow, Diffuse };
inline constexpr BenchRayKind kBenchRayKinds[] = {BenchRayKind::Primary, BenchRayKind::Shadow, BenchRayKind::Diffuse};
const char* to_string(BenchRayKind kind);
crosscheck::RayKind crosscheck_kind(BenchRayKind kind);

enum class QueryKind { Closest, Any };
const char* to_string(QueryKind query);

// The scale series (every family at 1k, 4k, ..., max_triangles, powers of 4) followed by the meshes of
// $TWINRAY_SHARED/data/meshes that exist (bunny, dragon, sponza) and, with them, the interior views
// scenes/sponza-interior.json, scenes/dragon-closeup.json and scenes/cornell-box-reference.json; then the
// user's own scene files (`extra`), named by their stem (made unique with -2, -3, ...): a bare mesh (.obj,
// .ply) in family "mesh", a scene file (.json, Mitsuba .xml) with its own camera and lights in family "view".
std::vector<BenchSceneSpec> scene_specs(std::size_t max_triangles, const std::optional<std::filesystem::path>& shared,
                                        const std::vector<std::filesystem::path>& extra = {});

// Rays per ray set (same for every backend and thread count).
void set_rays_per_set(std::size_t count);
std::size_t rays_per_set();

// The scene for `spec`, loaded or generated on first use.
const Scene& scene_for(const BenchSceneSpec& spec);
// A built backend for the current scene (built once, kept until the scene changes).
const Backend& backend_for(const BenchSceneSpec& spec, const std::string& backend_name);
// Replaces the cached backend (the build benchmark hands over the one it built last).
void keep_backend(const BenchSceneSpec& spec, const std::string& backend_name, std::unique_ptr<Backend> backend);
// The rays of one kind for the current scene, generated once with `embree` as the hit source.
const std::vector<Ray>& rays_for(const BenchSceneSpec& spec, BenchRayKind kind);

// Reference rates measured on embree-fast, keyed by a string naming scene, kind, query and threads.
// Units are whatever the caller stores (rays/s for traversal, primitives/s for builds).
std::optional<double> reference_rate(const std::string& key);
void store_reference_rate(const std::string& key, double rate);

}  // namespace twinray::bench
