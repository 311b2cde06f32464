// The renderer is one code path over every backend: the same scene, seed and spp through bvh, embree and
// brute give the same image (identical hits give bit-identical images; a few rays that graze an edge may
// differ, hence the small tolerances). Also: the render setup leaves out what a scene does not need.

#include "render_test_util.h"

#include "core/scene/scene_loader.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace twinray {
namespace {

using namespace twinray::test;

Scene small_mixed_scene() {
  // Triangles and spheres, every material, an area light, an emissive sphere and an environment.
  Scene scene = empty_scene({0, 1, 4}, {0, 0.5f, 0}, {0, 1, 0}, 45.0f, 24, 18);
  constant_environment(scene, glm::vec3(0.2f, 0.25f, 0.3f));
  add_quad(scene, {-3, 0, 3}, {6, 0, 0}, {0, 0, -6}, add_material(scene, diffuse({0.6f, 0.6f, 0.5f})));
  add_box(scene, {-1.6f, 0, -1}, {-0.6f, 1.2f, 0}, add_material(scene, diffuse({0.7f, 0.2f, 0.2f})), false);
  add_sphere(scene, {0.2f, 0.5f, 0.2f}, 0.5f, add_material(scene, glass(1.5f)));
  add_sphere(scene, {1.3f, 0.6f, -0.5f}, 0.6f, add_material(scene, mirror({0.9f, 0.9f, 0.9f})));
  add_quad(scene, {-0.5f, 2.5f, -0.5f}, {0, 0, 1}, {1, 0, 0}, add_material(scene, emissive({8, 8, 7})));
  add_sphere(scene, {1.5f, 2.0f, 1.0f}, 0.2f, add_material(scene, emissive({10, 6, 3})));
  return scene;
}

TEST(RenderBackendsAgree, BvhEmbreeAndBruteGiveTheSameImage) {
  const Scene scene = small_mixed_scene();
  RenderOptions o;
  o.spp = 16;
  o.seed = 5;
  const Rendered reference = render_scene(scene, o, "brute");
  const glm::dvec3 ref_mean = image_mean(reference.mean);
  for (const char* name : {"bvh", "embree"}) {
    const Rendered r = render_scene(scene, o, name);
    EXPECT_LT(rel_mse(r.mean, reference.mean), 1e-4) << name;
    const glm::dvec3 mean = image_mean(r.mean);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], ref_mean[c], 1e-4 * ref_mean[c]) << name << " channel " << c;
  }
}

TEST(RenderBackendsAgree, ImageDoesNotDependOnThreadCount) {
  const Scene scene = small_mixed_scene();
  RenderOptions o;
  o.spp = 4;
  o.seed = 9;
  const Rendered all = render_scene(scene, o, "bvh");
  Rendered one_thread;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one_thread = render_scene(scene, o, "bvh");
  }
  EXPECT_EQ(all.mean.data, one_thread.mean.data);
}

TEST(RenderFeatures, LeftOutWhatTheSceneDoesNotNeed) {
  const std::filesystem::path scenes = std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes";
  const BackendTraits traits;
  {
    const Scene cornell = load_scene(scenes / "cornell-box-reference.json");
    const RenderSetup setup(cornell, RenderOptions{}, traits);
    const RenderFeatures& f = setup.features();
    EXPECT_FALSE(f.environment);
    EXPECT_FALSE(f.env_sampling_tables);
    EXPECT_TRUE(f.light_sampler);
    EXPECT_EQ(f.triangle_light_count, 2u);
    EXPECT_FALSE(f.sphere_geometry);
    EXPECT_FALSE(f.sphere_lights);
    const auto left = f.left_out();
    EXPECT_NE(std::find(left.begin(), left.end(), "env sampling tables (no environment)"), left.end());
    EXPECT_NE(std::find(left.begin(), left.end(), "sphere code paths (no spheres)"), left.end());
  }
  {
    const Scene furnace = load_scene(scenes / "white-furnace.json");
    const RenderSetup setup(furnace, RenderOptions{}, traits);
    const RenderFeatures& f = setup.features();
    EXPECT_TRUE(f.environment);
    EXPECT_FALSE(f.env_sampling_tables) << "a constant environment needs no tables";
    EXPECT_TRUE(f.sphere_geometry);
    EXPECT_FALSE(f.sphere_lights);
    EXPECT_EQ(f.triangle_light_count, 0u);
  }
  {
    // No emitters and no environment: nothing to sample.
    Scene dark = empty_scene({0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 40.0f, 4, 4);
    add_quad(dark, {-1, -1, 0}, {2, 0, 0}, {0, 2, 0}, add_material(dark, diffuse(glm::vec3(0.5f))));
    const RenderSetup setup(dark, RenderOptions{}, traits);
    EXPECT_FALSE(setup.features().light_sampler);
    EXPECT_EQ(setup.lights(), nullptr);
    const auto left = setup.features().left_out();
    EXPECT_NE(std::find(left.begin(), left.end(), "light sampling (no emitters)"), left.end());
  }
  {
    const Scene mixed = small_mixed_scene();
    const RenderSetup setup(mixed, RenderOptions{}, traits);
    EXPECT_TRUE(setup.features().sphere_lights);
    EXPECT_EQ(setup.features().sphere_light_count, 1u);
    const auto left = setup.features().left_out();
    ASSERT_EQ(left.size(), 1u);
    EXPECT_EQ(left[0], "env sampling tables (constant environment needs none)");
  }
}

}  // namespace
}  // namespace twinray
