// The caustic light tracer (core/render/light_tracer.h) and its partition of path space with the path
// tracer: its normalisation against the path tracer's direct lighting, the partition's unbiasedness and
// noise on the mirror-and-glass Cornell box, the features that switch it on, and its determinism.

#include "render_test_util.h"

#include "core/camera/pinhole_camera.h"
#include "core/render/light_tracer.h"
#include "core/render/light_transport.h"
#include "core/scene/scene_loader.h"
#include "harness/compare/image_comparison.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <numbers>

namespace twinray {
namespace {

using namespace twinray::test;

// A diffuse floor under a small one-sided quad light facing down; the camera above the light's plane sees
// the floor and the light's black back, never its emitting front. Only L D E paths reach the camera at
// max_depth 2.
Scene lit_floor_scene(int size) {
  Scene scene = empty_scene({0.0f, 2.0f, 2.5f}, {0.0f, 0.0f, 0.0f}, {0, 1, 0}, 50.0f, size, size);
  add_quad(scene, {-1.5f, 0.0f, 1.5f}, {3.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -3.0f}, add_material(scene, diffuse({0.7f, 0.5f, 0.3f})));
  add_quad(scene, {-0.3f, 1.0f, -0.3f}, {0.6f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.6f}, add_material(scene, emissive({10, 9, 8})));
  return scene;
}

// A scene's bvh, light sampler, context and camera: what a LightTracer reads (it keeps references).
struct LightTracingSetup {
  explicit LightTracingSetup(const Scene& scene)
      : backend(built_backend(scene)),
        lights(scene, nullptr),
        ctx(SceneContext::make(scene, *backend, nullptr, &lights)),
        camera(scene.camera) {}
  std::unique_ptr<Backend> backend;
  LightSampler lights;
  SceneContext ctx;
  PinholeCamera camera;
};

// Mean and variance of the mean of the light tracer alone: N = spp * pixels light paths.
compare::NoisyImage light_traced_image(const Scene& scene, const IntegratorSettings& settings, int spp,
                                       std::uint64_t seed, LightPathSet paths) {
  const ScopedFlushDenormals ftz;
  const LightTracingSetup setup(scene);
  const PinholeCamera& camera = setup.camera;
  const LightTracer tracer(setup.ctx, settings, camera, SamplerKind::Independent, seed, paths);
  Film film(camera.width(), camera.height(), AuxChannels{});
  film.enable_splats();
  std::vector<Splat> splats;
  TraceCounters counters;
  std::uint64_t nonfinite = 0;
  const std::uint64_t n = static_cast<std::uint64_t>(spp) * static_cast<std::uint64_t>(camera.width() * camera.height());
  tracer.trace(0, n, splats, counters, nonfinite);
  EXPECT_EQ(nonfinite, 0u);
  EXPECT_GT(splats.size(), n / 10) << "most light paths should reach the camera";
  for (const Splat& s : splats) film.add_splat(s.pixel, glm::dvec3(s.value));
  film.set_splat_samples_per_pixel(static_cast<std::uint64_t>(spp));
  return {film.mean_image(), film.variance_of_mean_image()};
}

TEST(CausticLightTracer, AllDirectLightingAgreesWithThePathTracer) {
  // Light tracing every L D E path (LightPathSet::AllDiffuse) estimates what the path tracer's direct
  // lighting does: a wrong importance (cos^3, image area, pixel count) or emission weight shows as a
  // factor. Independent samplers on both sides, so the per-pixel variances are exact estimates.
  const Scene scene = lit_floor_scene(32);
  IntegratorSettings settings;
  settings.max_depth = 2;
  const compare::NoisyImage light = light_traced_image(scene, settings, 256, 3, LightPathSet::AllDiffuse);

  RenderOptions o;
  o.settings = settings;
  o.spp = 256;
  o.seed = 4;
  o.sampler = SamplerKind::Independent;
  const Rendered path = render_scene(scene, o);
  EXPECT_FALSE(path.features.caustic_light_tracing) << "no mirror or glass: the light tracer stays off";
  const compare::NoisyImage path_image{path.mean, path.variance_of_mean};

  const compare::Comparison c = compare::compare_images(light, path_image, 4);
  EXPECT_TRUE(c.agree) << "largest |z| " << c.max_abs_z << " over threshold " << c.threshold;
  const double light_mean = image_mean(light.mean).x, path_mean = image_mean(path.mean).x;
  EXPECT_GT(path_mean, 0.05);
  EXPECT_NEAR(light_mean / path_mean, 1.0, 0.01);

  // The test can fail: 3% too much light stands out in the regions (measured: largest |z| 6.7 against a
  // threshold of 4.3; the unscaled images: 1.9, and the image means agree to 0.13%).
  compare::NoisyImage scaled = light;
  for (float& v : scaled.mean.data) v *= 1.03f;
  const compare::Comparison cs = compare::compare_images(scaled, path_image, 4);
  EXPECT_FALSE(cs.agree) << "largest |z| " << cs.max_abs_z << " (measured 6.7) under threshold " << cs.threshold;
}

TEST(CausticLightTracer, CausticsModeOnlyConnectsAfterASpecularFirstHit) {
  // The same floor and light without mirror or glass: no light path starts with a specular bounce.
  const Scene scene = lit_floor_scene(16);
  const ScopedFlushDenormals ftz;
  const LightTracingSetup setup(scene);
  const LightTracer tracer(setup.ctx, IntegratorSettings{}, setup.camera, SamplerKind::Sobol, 1);
  std::vector<Splat> splats;
  TraceCounters counters;
  std::uint64_t nonfinite = 0;
  tracer.trace(0, 4096, splats, counters, nonfinite);
  EXPECT_TRUE(splats.empty());
  EXPECT_EQ(counters.shadow_rays, 0u);
}

TEST(CausticLightTracer, EmissionSamplesCarryTheLightsPowerAndLeaveTheirFront) {
  // Two quads of different radiance, an emissive sphere and a constant environment: light paths start only
  // on the surfaces, and the mean weight of a start is the emitted power pi sum(A Le) exactly (the weight
  // depends only on which light was picked: pi Le A / pmf). Directions are cosine-distributed about the
  // emitting side: E[cos] = 2/3.
  Scene scene;
  add_quad(scene, {0, 2, 0}, {1, 0, 0}, {0, 0, 1}, add_material(scene, emissive({2, 2, 2})));   // faces down, A = 1
  add_quad(scene, {3, 0, 0}, {0, 0, 2}, {0, 1, 0}, add_material(scene, emissive({1, 0.5f, 0.25f})));  // A = 2
  add_sphere(scene, {-3, 1, 0}, 0.5f, add_material(scene, emissive({4, 4, 4})));
  constant_environment(scene, glm::vec3(1.0f));
  const auto sky = EnvironmentLight::create(scene.environment);
  const LightSampler lights(scene, sky.get());
  ASSERT_TRUE(lights.has_environment());
  ASSERT_TRUE(lights.has_surface_lights());
  const double pi = std::numbers::pi;
  const glm::dvec3 power =
      pi * (1.0 * glm::dvec3(2, 2, 2) + 2.0 * glm::dvec3(1, 0.5, 0.25) + 4.0 * pi * 0.25 * glm::dvec3(4, 4, 4));
  Rng rng(8, 8);
  constexpr int n = 200000;
  glm::dvec3 sum(0.0), sum_sq(0.0);
  double cos_sum = 0.0;
  for (int i = 0; i < n; ++i) {
    EmissionSample es;
    ASSERT_TRUE(lights.sample_emission({rng.next_float(), rng.next_float()}, {rng.next_float(), rng.next_float()}, es));
    sum += glm::dvec3(es.weight);
    sum_sq += glm::dvec3(es.weight) * glm::dvec3(es.weight);
    const float c = glm::dot(es.dir, es.normal);
    ASSERT_GT(c, 0.0f);
    cos_sum += c;
    if (es.point.x >= 0.0f && es.point.x <= 1.0f) {  // the downward quad (the others lie at x = 3 and x < -2)
      EXPECT_NEAR(es.point.y, 2.0f, 1e-6f);
      EXPECT_EQ(es.normal, glm::vec3(0, -1, 0));
    }
  }
  // The weight takes one of three values (one per light); 4 standard errors of its mean bound the error.
  const glm::dvec3 mean = sum / static_cast<double>(n);
  for (int c = 0; c < 3; ++c) {
    const double se = std::sqrt((sum_sq[c] / n - mean[c] * mean[c]) / (n - 1));
    EXPECT_NEAR(mean[c], power[c], 4.0 * se) << "channel " << c;
  }
  EXPECT_NEAR(cos_sum / n, 2.0 / 3.0, 4.0 * std::sqrt(1.0 / 18.0 / n));
}

Scene mirror_glass_box(int size) {
  Scene scene = load_scene(std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes" / "cornell-mirror-glass.json");
  scene.camera.width = size;
  scene.camera.height = size;
  return scene;
}

// `batches` renders with seeds 0, 1, ...: the mean and the variance of the mean from the batches (valid
// for the Sobol sampler too), as twinray compare measures them.
compare::NoisyImage batch_image(const Scene& scene, RenderOptions o, int batches) {
  const int w = scene.camera.width, h = scene.camera.height;
  std::vector<double> sum(static_cast<std::size_t>(w * h * 3), 0.0), sum_sq(sum.size(), 0.0);
  for (int b = 0; b < batches; ++b) {
    o.seed = static_cast<std::uint64_t>(100 + b);
    const Rendered r = render_scene(scene, o, "bvh8");
    for (std::size_t i = 0; i < sum.size(); ++i) {
      const double v = r.mean.data[i];
      sum[i] += v;
      sum_sq[i] += v * v;
    }
  }
  compare::NoisyImage out{Image(w, h, 3), Image(w, h, 3)};
  const double n = batches;
  for (std::size_t i = 0; i < sum.size(); ++i) {
    const double mean = sum[i] / n;
    out.mean.data[i] = static_cast<float>(mean);
    out.variance_of_mean.data[i] = static_cast<float>(std::max(0.0, sum_sq[i] / n - mean * mean) / (n - 1.0));
  }
  return out;
}

double noise_rel_mse(const compare::NoisyImage& image, const Image& truth) {
  return compare::expected_rel_mse(image, truth);
}

TEST(CausticLightTracer, PartitionIsUnbiasedAndQuieterOnTheMirrorGlassBox) {
  // With --caustics off the path tracer counts every path; with auto the light tracer takes over the
  // caustics seen on diffuse surfaces. Same expectation (agree within noise, region by region), and the
  // caustic noise, which dominates this scene's path-traced error, drops at the same spp: measured 6.6x
  // here (relMSE 2.4e-3 against 1.6e-2) and 5.3x at 256 x 256, 64 spp (docs/rendering.md); asserted > 2x.
  //
  // The agreement test compares against the path tracer at 8x the spp (256): its caustics come from rare
  // BSDF samples that hit the light through the mirror, so at low spp its estimate is skewed (most batches
  // miss them and read low, with a variance that does not show it): at 48 x 48 and 8 batches of 16 spp,
  // dim ceiling regions read 26% low with |z| up to 10 against the light tracer, while at 4096 spp they
  // agree with it to 2%. Regions of 8 x 8 pixels (4 x 4 grid) pool enough samples for the z-test.
  const Scene scene = mirror_glass_box(32);
  RenderOptions o;
  o.spp = 32;
  constexpr int kBatches = 8;
  const compare::NoisyImage with = batch_image(scene, o, kBatches);
  o.caustics = CausticsMode::Off;
  const compare::NoisyImage without = batch_image(scene, o, kBatches);
  o.spp = 256;
  const compare::NoisyImage without_more = batch_image(scene, o, kBatches);

  const compare::Comparison c = compare::compare_images(with, without_more, 4);
  EXPECT_TRUE(c.agree) << "largest |z| " << c.max_abs_z << " over threshold " << c.threshold;
  const double rel_with = noise_rel_mse(with, with.mean), rel_without = noise_rel_mse(without, with.mean);
  EXPECT_GT(rel_without / rel_with, 2.0) << "relMSE with caustics " << rel_with << ", without " << rel_without;
}

// Glass and mirror spheres on a floor under a large light and a dim sky: the path tracer finds the
// caustics often enough here for a z-test at equal spp, at every depth limit.
Scene big_light_caustics(int size) {
  Scene scene = empty_scene({0.0f, 1.6f, 3.2f}, {0.0f, 0.4f, 0.0f}, {0, 1, 0}, 45.0f, size, size);
  constant_environment(scene, glm::vec3(0.02f, 0.025f, 0.03f));
  add_quad(scene, {-2, 0, 2}, {4, 0, 0}, {0, 0, -4}, add_material(scene, diffuse({0.7f, 0.7f, 0.7f})));
  add_sphere(scene, {-0.55f, 0.5f, 0.0f}, 0.5f, add_material(scene, glass(1.5f)));
  add_sphere(scene, {0.6f, 0.45f, -0.3f}, 0.45f, add_material(scene, mirror({0.9f, 0.8f, 0.7f})));
  add_quad(scene, {-0.6f, 2.0f, -0.6f}, {1.2f, 0, 0}, {0, 0, 1.2f}, add_material(scene, emissive({8, 8, 8})));
  return scene;
}

TEST(CausticLightTracer, PartitionIsExactAtEveryDepthLimitWithAnEnvironment) {
  // max_depth 2 (no caustic path fits: the light tracer may connect nothing), 3 (E D S L only), 4, and
  // unlimited with Russian roulette from segment 2 on, so that both sides' roulettes play on caustics.
  // Power: with the splats dropped (the path tracer still leaving the caustics out) the largest |z| was 6.1,
  // 26 and 18 at depths 3, 4 and unlimited (threshold 4.3); as it is, 2.7 to 2.9.
  const Scene scene = big_light_caustics(24);
  for (const int max_depth : {2, 3, 4, -1}) {
    RenderOptions o;
    o.spp = 64;
    o.settings.max_depth = max_depth;
    o.settings.rr_depth = max_depth < 0 ? 2 : 5;
    const compare::NoisyImage with = batch_image(scene, o, 6);
    o.caustics = CausticsMode::Off;
    const compare::NoisyImage without = batch_image(scene, o, 6);
    const compare::Comparison c = compare::compare_images(with, without, 4);
    EXPECT_TRUE(c.agree) << "max_depth " << max_depth << ": largest |z| " << c.max_abs_z << " over " << c.threshold;
    if (max_depth == 2) {
      EXPECT_EQ(with.mean.data, without.mean.data) << "nothing to light-trace at depth 2";
    }
  }
}

TEST(CausticLightTracer, SwitchedOnOnlyWhereTheSceneNeedsIt) {
  const Scene box = mirror_glass_box(8);
  RenderOptions o;
  const BackendTraits traits{};
  EXPECT_TRUE(RenderSetup(box, o, traits).features().caustic_light_tracing);
  o.caustics = CausticsMode::Off;
  EXPECT_FALSE(RenderSetup(box, o, traits).features().caustic_light_tracing);
  o.caustics = CausticsMode::Auto;
  o.integrator = IntegratorKind::Direct;
  EXPECT_FALSE(RenderSetup(box, o, traits).features().caustic_light_tracing);
  o.integrator = IntegratorKind::Path;
  o.settings.strategy = SamplingStrategy::Bsdf;  // no light sampler is built
  EXPECT_FALSE(RenderSetup(box, o, traits).features().caustic_light_tracing);

  // Mirror and glass under an environment alone: no area light starts a light path.
  Scene sky = empty_scene({0, 1, 4}, {0, 0.5f, 0}, {0, 1, 0}, 45.0f, 8, 8);
  constant_environment(sky, glm::vec3(1.0f));
  add_sphere(sky, {0, 0.5f, 0}, 0.5f, add_material(sky, glass(1.5f)));
  add_quad(sky, {-3, 0, 3}, {6, 0, 0}, {0, 0, -6}, add_material(sky, diffuse({0.5f, 0.5f, 0.5f})));
  const RenderFeatures f = RenderSetup(sky, RenderOptions{}, traits).features();
  EXPECT_FALSE(f.caustic_light_tracing);
  const auto left = f.left_out();
  EXPECT_NE(std::find(left.begin(), left.end(), "caustic light tracing (no area lights)"), left.end());
}

TEST(CausticLightTracer, ImageIsBitIdenticalAcrossBackendsAndThreadCounts) {
  const Scene scene = mirror_glass_box(32);
  RenderOptions o;
  o.spp = 4;
  o.seed = 7;
  const Rendered reference = render_scene(scene, o, "bvh8");
  ASSERT_TRUE(reference.features.caustic_light_tracing);
  EXPECT_GT(reference.stats.splats, 0u);
  EXPECT_EQ(reference.stats.light_paths, 4u * 32u * 32u);
  for (const char* name : {"bvh", "brute"}) {
    const Rendered r = render_scene(scene, o, name);
    EXPECT_EQ(r.mean.data, reference.mean.data) << name;
    EXPECT_EQ(r.variance_of_mean.data, reference.variance_of_mean.data) << name;
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    const Rendered one_thread = render_scene(scene, o, "bvh8");
    EXPECT_EQ(one_thread.mean.data, reference.mean.data);
    EXPECT_EQ(one_thread.variance_of_mean.data, reference.variance_of_mean.data);
  }

  // --time renders passes of 1 spp (light paths s P .. (s + 1) P - 1 in pass s): the same image as --spp
  // with the number of passes it managed.
  RenderOptions timed = o;
  timed.time_budget_seconds = 0.05;
  const Rendered progressive = render_scene(scene, timed, "bvh8");
  ASSERT_GE(progressive.stats.spp, 1);
  o.spp = progressive.stats.spp;
  const Rendered at_once = render_scene(scene, o, "bvh8");
  EXPECT_EQ(progressive.stats.light_paths, at_once.stats.light_paths);
  EXPECT_EQ(progressive.mean.data, at_once.mean.data);
}

}  // namespace
}  // namespace twinray
