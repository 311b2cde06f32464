// The plugin C ABI and its loader, with the example plugins of tests/plugins (built as shared libraries).

#include "backends/brute/brute_backend.h"
#include "backends/plugin/plugin_backend.h"
#include "backends/registry.h"
#include "core/sampling/rng.h"
#include "core/util/input_error.h"
#include "ray_test_util.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace twinray {
namespace {

using test::kInf;
using test::kNaN;
using test::make_ray;

const std::filesystem::path kBrutePlugin = TWINRAY_TEST_BRUTE_PLUGIN;
const std::filesystem::path kWrongAbiPlugin = TWINRAY_TEST_WRONG_ABI_PLUGIN;
const std::filesystem::path kNoEntryPlugin = TWINRAY_TEST_NO_ENTRY_PLUGIN;

// A grid of 2 n^2 triangles in z = 0 over [0, n]^2, random triangles above it, spheres of varied sizes;
// geometry ids interleave meshes and spheres.
SceneGeometry make_mixed_scene() {
  SceneGeometry g;
  constexpr int kN = 6;
  TriangleMesh grid;
  grid.geom_id = 0;
  for (int j = 0; j <= kN; ++j)
    for (int i = 0; i <= kN; ++i) grid.positions.emplace_back(static_cast<float>(i), static_cast<float>(j), 0.0f);
  for (int j = 0; j < kN; ++j)
    for (int i = 0; i < kN; ++i) {
      const auto v = static_cast<unsigned>(j * (kN + 1) + i);
      grid.indices.emplace_back(v, v + 1, v + kN + 2);
      grid.indices.emplace_back(v, v + kN + 2, v + kN + 1);
    }
  grid.positions.reserve(grid.positions.size() + 1);
  g.meshes.push_back(grid);

  Rng rng(5, 9);
  TriangleMesh soup;
  soup.geom_id = 2;
  for (unsigned k = 0; k < 40; ++k) {
    const glm::vec3 c{rng.next_float() * 6.0f, rng.next_float() * 6.0f, 0.5f + rng.next_float() * 3.0f};
    for (int v = 0; v < 3; ++v)
      soup.positions.push_back(c + glm::vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f));
    soup.indices.emplace_back(3 * k, 3 * k + 1, 3 * k + 2);
  }
  soup.positions.reserve(soup.positions.size() + 1);
  g.meshes.push_back(soup);

  const std::uint32_t sphere_ids[] = {1, 3, 4, 5};
  for (std::uint32_t k = 0; k < 4; ++k) {
    Sphere s;
    s.geom_id = sphere_ids[k];
    s.center = {1.0f + 1.3f * static_cast<float>(k), 4.0f - 0.7f * static_cast<float>(k), 1.5f};
    s.radius = 0.2f + 0.25f * static_cast<float>(k);
    g.spheres.push_back(s);
  }
  return g;
}

std::vector<Ray> rays_over_the_grid(std::size_t n, std::uint64_t seed) {
  Rng rng(seed, 1);
  std::vector<Ray> rays;
  for (std::size_t k = 0; k < n; ++k) {
    const glm::vec3 org{rng.next_float() * 8.0f - 1.0f, rng.next_float() * 8.0f - 1.0f, 2.0f + rng.next_float() * 4.0f};
    const glm::vec3 target{rng.next_float() * 6.0f, rng.next_float() * 6.0f, rng.next_float() * 2.0f};
    rays.push_back(make_ray(org, target - org, 0.0f, k % 4 == 0 ? 0.5f + rng.next_float() : kInf));
  }
  return rays;
}

TEST(PluginBackend, LoadsTheExamplePluginWithItsNameAndTraits) {
  auto backend = load_plugin_backend(kBrutePlugin);
  EXPECT_EQ(backend->name(), "plugin:brute-c");
  const BackendTraits t = backend->traits();
  EXPECT_TRUE(t.counts_traversal);
  EXPECT_TRUE(t.honours_ties);
  EXPECT_FALSE(t.watertight);
  // The registry resolves plugin:PATH to the same loader.
  EXPECT_EQ(make_backend("plugin:" + kBrutePlugin.string())->name(), "plugin:brute-c");
}

// The example plugin is a correct backend: it agrees with the built-in brute-force oracle.
TEST(PluginBackend, ExamplePluginCrosschecksAgainstBrute) {
  const SceneGeometry g = make_mixed_scene();
  auto plugin = load_plugin_backend(kBrutePlugin);
  auto brute = make_brute_backend();
  plugin->build(g);
  brute->build(g);
  const std::vector<Ray> rays = rays_over_the_grid(3000, 17);
  std::size_t found = 0, on_spheres = 0;
  for (std::size_t k = 0; k < rays.size(); ++k) {
    Hit a, b;
    const bool ha = plugin->intersect(rays[k], a);
    const bool hb = brute->intersect(rays[k], b);
    ASSERT_EQ(ha, hb) << k;
    EXPECT_EQ(plugin->occluded(rays[k]), hb) << k;
    if (!hb) continue;
    ++found;
    on_spheres += b.geom_id != 0 && b.geom_id != 2 ? 1 : 0;  // meshes are 0 and 2
    EXPECT_EQ(a.geom_id, b.geom_id) << k;
    EXPECT_EQ(a.prim_id, b.prim_id) << k;
    // Double-precision Moller-Trumbore against the watertight float test: t agrees to a few float ulps.
    EXPECT_NEAR(a.t, b.t, 4e-6f * b.t) << k;
    EXPECT_NEAR(a.u, b.u, 1e-5f) << k;
    EXPECT_NEAR(a.v, b.v, 1e-5f) << k;
    EXPECT_LT(glm::length(a.ng - b.ng), 1e-6f) << k;
  }
  EXPECT_GT(found, rays.size() / 2);
  EXPECT_GT(on_spheres, 50u);
}

// The optional batch entry point (present in the example) and the fallback loop (occluded_batch is NULL)
// both give the single-ray answers; invalid rays are misses and never reach the plugin.
TEST(PluginBackend, BatchesMatchSingleRaysAndInvalidRaysNeverReachThePlugin) {
  const SceneGeometry g = make_mixed_scene();
  auto plugin = load_plugin_backend(kBrutePlugin);
  plugin->build(g);
  std::vector<Ray> rays = rays_over_the_grid(600, 23);
  const glm::vec3 org{3, 3, 5}, down{0, 0, -1};
  const std::vector<Ray> invalid = {make_ray({kNaN, 0, 0}, down), make_ray(org, {0, 0, 0}), make_ray(org, {kInf, 0, 1}),
                                    make_ray(org, down, -1.0f), make_ray(org, down, 2.0f, 1.0f),
                                    make_ray(org, down, 0.0f, kNaN)};
  for (std::size_t k = 0; k < invalid.size(); ++k) rays.insert(rays.begin() + static_cast<std::ptrdiff_t>(k * 97), invalid[k]);

  std::vector<Hit> hits(rays.size());
  std::vector<std::uint8_t> occ(rays.size(), 9);
  plugin->intersect(rays, hits, nullptr);
  plugin->occluded(rays, occ, nullptr);
  for (std::size_t k = 0; k < rays.size(); ++k) {
    Hit single;
    const bool h = plugin->intersect(rays[k], single);
    ASSERT_EQ(hits[k].found(), h) << k;
    EXPECT_EQ(occ[k], h ? 1 : 0) << k;
    if (!h) continue;
    EXPECT_EQ(hits[k].t, single.t) << k;
    EXPECT_EQ(hits[k].geom_id, single.geom_id) << k;
    EXPECT_EQ(hits[k].prim_id, single.prim_id) << k;
  }

  // The example counts one primitive test per primitive per intersect query: invalid rays add none.
  QueryStats stats;
  std::vector<Hit> invalid_hits(invalid.size());
  plugin->intersect(invalid, invalid_hits, &stats);
  for (const Ray& r : invalid) {
    Hit h;
    h.geom_id = 3;
    EXPECT_FALSE(plugin->intersect(r, h, &stats));
    EXPECT_FALSE(h.found());
    EXPECT_FALSE(plugin->occluded(r, &stats));
  }
  EXPECT_EQ(stats.queries, 3 * invalid.size());
  EXPECT_EQ(stats.primitives_tested, 0u);
  Hit h;
  plugin->intersect(make_ray(org, down), h, &stats);
  EXPECT_EQ(stats.primitives_tested, g.primitive_count());
}

TEST(PluginBackend, BuildStatsComeFromTheSceneAndThePlugin) {
  const SceneGeometry g = make_mixed_scene();
  auto plugin = load_plugin_backend(kBrutePlugin);
  plugin->build(g);
  const BuildStats s = plugin->build_stats();
  EXPECT_EQ(s.triangles, g.triangle_count());
  EXPECT_EQ(s.spheres, 4u);
  EXPECT_TRUE(s.built_triangles);
  EXPECT_TRUE(s.built_spheres);
  EXPECT_GT(s.memory_bytes, 0u);  // reported by the plugin's optional build_stats
}

TEST(PluginBackend, BuildFailureCarriesThePluginsMessage) {
  SceneGeometry g;
  Sphere s;
  s.geom_id = 7;
  s.radius = 0.0f;  // the example plugin rejects it
  g.spheres.push_back(s);
  auto plugin = load_plugin_backend(kBrutePlugin);
  try {
    plugin->build(g);
    FAIL() << "build should have failed";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("plugin:brute-c"), std::string::npos) << what;
    EXPECT_NE(what.find("sphere with geom_id 7 has radius <= 0"), std::string::npos) << what;
  }
}

// Each load failure is an InputError naming the file and saying what is wrong.
void expect_load_error(const std::filesystem::path& path, const std::string& expected) {
  try {
    load_plugin_backend(path);
    FAIL() << "loading " << path << " should have failed";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(e.message().find(expected), std::string::npos) << e.what();
  }
}

TEST(PluginBackend, LoadErrorsAreInputErrors) {
  expect_load_error("/nonexistent/libnothing.so", "not found");

  const std::filesystem::path text = std::filesystem::temp_directory_path() / "twinray_test_not_a_library.so";
  std::ofstream(text) << "this is not an ELF file\n";
  expect_load_error(text, "cannot load it as a shared library");
  std::filesystem::remove(text);

  expect_load_error(kNoEntryPlugin, "does not export twinray_plugin_entry");
  expect_load_error(kWrongAbiPlugin, "plugin ABI version mismatch: the plugin was built for version 2, this "
                                     "twinray implements version 1");
}

}  // namespace
}  // namespace twinray
