#include "bench/bench_scenes.h"

#include "backends/registry.h"
#include "harness/crosscheck/ray_generation.h"
#include "core/scene/mesh_file.h"
#include "core/scene/scene_loader.h"
#include "core/util/fp_mode.h"

#include <fmt/core.h>

#include <algorithm>
#include <array>
#include <cstdio>

namespace twinray::bench {

namespace {

// Seeds are fixed: the same binary traces the same rays on every run, so runs can be compared.
constexpr std::uint64_t kGeometrySeed = 7;
constexpr std::uint64_t kRaySeed = 11;

struct CurrentScene {
  std::string name;
  std::unique_ptr<Scene> scene;
  std::map<std::string, std::unique_ptr<Backend>> backends;
  std::map<BenchRayKind, std::vector<Ray>> rays;
};

CurrentScene& current() {
  static CurrentScene c;
  return c;
}

std::size_t& rays_setting() {
  static std::size_t n = std::size_t{1} << 16;
  return n;
}

std::map<std::string, double>& reference_rates() {
  static std::map<std::string, double> rates;
  return rates;
}

std::string size_label(std::size_t n) {
  if (n >= (std::size_t{1} << 20) && n % (std::size_t{1} << 20) == 0) return fmt::format("{}M", n >> 20);
  if (n >= 1024 && n % 1024 == 0) return fmt::format("{}k", n >> 10);
  return std::to_string(n);
}

}  // namespace

const char* to_string(BenchRayKind kind) {
  switch (kind) {
    case BenchRayKind::Primary: return "primary";
    case BenchRayKind::Shadow: return "shadow";
    case BenchRayKind::Diffuse: return "diffuse";
  }
  return "?";
}

crosscheck::RayKind crosscheck_kind(BenchRayKind kind) {
  switch (kind) {
    case BenchRayKind::Primary: return crosscheck::RayKind::Camera;
    case BenchRayKind::Shadow: return crosscheck::RayKind::Shadow;
    case BenchRayKind::Diffuse: return crosscheck::RayKind::Diffuse;
  }
  return crosscheck::RayKind::Camera;
}

const char* to_string(QueryKind query) { return query == QueryKind::Closest ? "closest" : "any"; }

std::vector<BenchSceneSpec> scene_specs(std::size_t max_triangles, const std::optional<std::filesystem::path>& shared,
                                        const std::vector<std::filesystem::path>& extra) {
  std::vector<BenchSceneSpec> specs;
  for (BenchFamily family : kAllBenchFamilies)
    for (std::size_t n = 1024; n <= max_triangles; n *= 4)
      specs.push_back({fmt::format("{}-{}", to_string(family), size_label(n)), std::string(to_string(family)), n, {}});
  if (shared) {
    const std::array<std::pair<const char*, const char*>, 3> meshes = {
        {{"bunny", "stanford-bunny.obj"}, {"dragon", "dragon_100k.ply"}, {"sponza", "dabrovic_sponza.obj"}}};
    for (const auto& [name, file] : meshes) {
      const std::filesystem::path path = *shared / "data" / "meshes" / file;
      if (std::filesystem::exists(path)) specs.push_back({name, "mesh", 0, path});
      else fmt::print(stderr, "twinray_bench: {} not found, scene '{}' left out\n", path.string(), name);
    }
    // Interior views of the same meshes: scene files with their own camera and lights, which read the
    // meshes through $TWINRAY_SHARED; and the closed Cornell box (36 triangles, every ray starts inside
    // the boxes of the leaves around it), where the leaf cost of the wide tree's collapse matters most.
    for (const char* name : {"sponza-interior", "dragon-closeup", "cornell-box-reference"}) {
      const std::filesystem::path path = std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes" / (std::string(name) + ".json");
      if (std::filesystem::exists(path)) specs.push_back({name, "view", 0, path});
      else fmt::print(stderr, "twinray_bench: {} not found, scene '{}' left out\n", path.string(), name);
    }
  }
  for (const std::filesystem::path& path : extra) {
    const std::string stem = path.stem().string();
    std::string name = stem;
    const auto taken = [&specs](const std::string& n) {
      return std::any_of(specs.begin(), specs.end(), [&n](const BenchSceneSpec& s) { return s.name == n; });
    };
    for (int k = 2; taken(name); ++k) name = fmt::format("{}-{}", stem, k);
    specs.push_back({name, is_mesh_file_extension(path) ? "mesh" : "view", 0, path});
  }
  return specs;
}

void set_rays_per_set(std::size_t count) { rays_setting() = count; }
std::size_t rays_per_set() { return rays_setting(); }

const Scene& scene_for(const BenchSceneSpec& spec) {
  CurrentScene& c = current();
  if (c.scene && c.name == spec.name) return *c.scene;
  // Backends point into the old scene's geometry: drop them first.
  c.backends.clear();
  c.rays.clear();
  c.scene.reset();
  if (spec.family == "mesh" || spec.family == "view") {
    c.scene = std::make_unique<Scene>(load_scene(spec.file));
  } else {
    const BenchFamily family = *parse_bench_family(spec.family);
    c.scene = std::make_unique<Scene>(bench_scene(bench_geometry(family, spec.target_triangles, kGeometrySeed), spec.name));
    if (family == BenchFamily::Terrain) {
      // The default framing camera looks along the height field's plane and sees mostly sky; from 35
      // degrees above, every primary ray lands on the terrain, as in a fly-over.
      c.scene->camera.position = {0.0f, 1.6f, 2.3f};
      c.scene->camera.look_at = {0.0f, -0.1f, 0.0f};
    }
  }
  c.name = spec.name;
  return *c.scene;
}

const Backend& backend_for(const BenchSceneSpec& spec, const std::string& backend_name) {
  const Scene& scene = scene_for(spec);
  std::unique_ptr<Backend>& slot = current().backends[backend_name];
  if (!slot) {
    slot = make_backend(backend_name);
    const ScopedFlushDenormals ftz;
    slot->build(scene.geometry);
  }
  return *slot;
}

void keep_backend(const BenchSceneSpec& spec, const std::string& backend_name, std::unique_ptr<Backend> backend) {
  scene_for(spec);
  current().backends[backend_name] = std::move(backend);
}

const std::vector<Ray>& rays_for(const BenchSceneSpec& spec, BenchRayKind kind) {
  const Scene& scene = scene_for(spec);
  auto it = current().rays.find(kind);
  if (it != current().rays.end()) return it->second;
  // The robust Embree backend finds the first hits that diffuse and shadow rays start from, so every
  // backend under test then traces exactly the same rays.
  const Backend& hit_source = backend_for(spec, "embree");
  const ScopedFlushDenormals ftz;
  std::vector<Ray> rays = crosscheck::generate_rays(crosscheck_kind(kind), scene, hit_source, rays_per_set(), kRaySeed);
  return current().rays.emplace(kind, std::move(rays)).first->second;
}

std::optional<double> reference_rate(const std::string& key) {
  const auto it = reference_rates().find(key);
  if (it == reference_rates().end()) return std::nullopt;
  return it->second;
}

void store_reference_rate(const std::string& key, double rate) { reference_rates()[key] = rate; }

}  // namespace twinray::bench
