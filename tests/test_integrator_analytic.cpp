// Integrators against closed-form answers. Tolerances: 4 standard errors of the estimate, the standard
// error computed from the per-pixel sample variance of the same render (plus 1e-6 for estimates that are
// exact up to float rounding and have zero variance).

#include "render_test_util.h"

#include "core/image/image_io.h"
#include "core/lights/environment_light.h"
#include "core/render/light_transport.h"
#include "core/render/path_integrator.h"
#include "core/render/direct_integrator.h"
#include "core/scene/procedural.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <numbers>

namespace twinray {
namespace {

using namespace twinray::test;

constexpr double kSigmas = 4.0;
constexpr double kRounding = 1e-5;

void expect_region(const Rendered& r, int channel, double expected, const std::function<bool(int, int)>& keep,
                   const char* what) {
  const RegionEstimate e = region_mean(r, channel, keep);
  ASSERT_GT(e.pixels, 0u) << what;
  EXPECT_NEAR(e.mean, expected, kSigmas * e.standard_error + kRounding * std::max(1.0, std::abs(expected)))
      << what << " channel " << channel << " over " << e.pixels << " pixels, standard error " << e.standard_error;
}

auto all_pixels = [](int, int) { return true; };

RenderOptions path_options(int spp, int max_depth = -1) {
  RenderOptions o;
  o.integrator = IntegratorKind::Path;
  o.spp = spp;
  o.settings.max_depth = max_depth;
  o.seed = 7;
  return o;
}

TEST(IntegratorAnalytic, WhiteFurnaceConvexAndNonConvex) {
  const glm::vec3 L(0.7f, 1.0f, 1.3f);
  for (int variant = 0; variant < 2; ++variant) {
    Scene scene = empty_scene({0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 40.0f, 16, 16);
    constant_environment(scene, L);
    const std::uint32_t white = add_material(scene, diffuse(glm::vec3(1.0f)));
    if (variant == 0) {
      add_sphere(scene, {0, 0, 0}, 1.0f, white);
    } else {
      // Two touching spheres and a box with a sphere sunk into it: light bounces between them.
      add_sphere(scene, {-0.5f, 0, 0}, 0.6f, white);
      add_sphere(scene, {0.5f, 0.1f, 0}, 0.6f, white);
      add_box(scene, {-1.2f, -1.2f, -0.8f}, {1.2f, -0.4f, 0.4f}, white, false);
    }
    for (IntegratorKind kind : {IntegratorKind::Path}) {
      RenderOptions o = path_options(64);
      o.integrator = kind;
      const Rendered r = render_scene(scene, o);
      for (int c = 0; c < 3; ++c) expect_region(r, c, L[c], all_pixels, variant == 0 ? "sphere" : "two spheres and a box");
      EXPECT_EQ(r.stats.nonfinite_samples, 0u);
    }
  }
}

TEST(IntegratorAnalytic, ConvexDiffuseObjectInUniformEnvironmentReflectsAlbedoTimesL) {
  const glm::vec3 L(2.0f, 1.0f, 0.5f);
  const glm::vec3 a(0.8f, 0.5f, 0.25f);
  Scene scene = empty_scene({0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 50.0f, 16, 16);
  constant_environment(scene, L);
  add_sphere(scene, {0, 0, 0}, 1.0f, add_material(scene, diffuse(a)));
  for (IntegratorKind kind : {IntegratorKind::Path, IntegratorKind::Direct}) {
    RenderOptions o = path_options(64);
    o.integrator = kind;
    const Rendered r = render_scene(scene, o);
    // Pixels entirely on the sphere: every sample's first hit had albedo a.
    auto on_sphere = [&r, &a](int x, int y) { return std::abs(r.albedo.at(x, y, 0) - a.x) < 1e-6f; };
    auto background = [&r](int x, int y) { return r.albedo.at(x, y, 0) == 0.0f; };
    for (int c = 0; c < 3; ++c) {
      expect_region(r, c, a[c] * L[c], on_sphere, "sphere");
      expect_region(r, c, L[c], background, "background");
    }
  }
}

// Camera inside a closed box whose inward faces emit Le and reflect with albedo a: L = Le (1 - a^k)/(1 - a)
// at max depth k (k segments: the camera ray plus k - 1 bounces), Le / (1 - a) unlimited.
TEST(IntegratorAnalytic, ClosedEmissiveEnclosureFollowsTheGeometricSeries) {
  const float Le = 1.0f, a = 0.5f;
  Scene scene = empty_scene({0.1f, 0.2f, 0.3f}, {0.1f, 0.2f, -1.0f}, {0, 1, 0}, 90.0f, 12, 12);
  add_box(scene, {-1, -1, -1}, {1, 1, 1}, add_material(scene, emissive(glm::vec3(Le), glm::vec3(a))), true);
  for (IntegratorKind kind : {IntegratorKind::Path, IntegratorKind::Direct}) {
    for (int k : {1, 2, 3, -1}) {
      if (kind == IntegratorKind::Direct && (k == 3 || k == -1)) continue;  // direct stops after one bounce
      RenderOptions o = path_options(48, k);
      o.integrator = kind;
      const Rendered r = render_scene(scene, o);
      const double expected = k < 0 ? Le / (1.0 - a) : Le * (1.0 - std::pow(a, k)) / (1.0 - a);
      SCOPED_TRACE(::testing::Message() << "integrator " << to_string(kind) << ", max depth " << k);
      expect_region(r, 0, expected, all_pixels, "enclosure");
    }
  }
}

// Path splitting (IntegratorSettings::splits) keeps the estimator unbiased: the enclosure's geometric series
// at depths 2, 3 (where the continuations carry the only bounce) and unlimited (roulette on split paths).
TEST(IntegratorAnalytic, SplitPathsFollowTheGeometricSeries) {
  const float Le = 1.0f, a = 0.5f;
  Scene scene = empty_scene({0.1f, 0.2f, 0.3f}, {0.1f, 0.2f, -1.0f}, {0, 1, 0}, 90.0f, 12, 12);
  add_box(scene, {-1, -1, -1}, {1, 1, 1}, add_material(scene, emissive(glm::vec3(Le), glm::vec3(a))), true);
  for (const std::uint32_t splits : {2u, 3u})
    for (int k : {2, 3, -1}) {
      RenderOptions o = path_options(48, k);
      o.settings.splits = splits;
      const Rendered r = render_scene(scene, o);
      const double expected = k < 0 ? Le / (1.0 - a) : Le * (1.0 - std::pow(a, k)) / (1.0 - a);
      SCOPED_TRACE(::testing::Message() << "splits " << splits << ", max depth " << k);
      expect_region(r, 0, expected, all_pixels, "enclosure");
    }
}

// Light connections (IntegratorSettings::light_connections) add a third strategy for the paths of three
// segments, whose MIS weights must sum to 1 with the path tracer's two: the enclosure's geometric series at
// depth 3 (where the connections share the last term, a^2 Le, with BSDF and light sampling at x2) and
// unlimited, with and without splitting (the weights use the split count).
TEST(IntegratorAnalytic, LightConnectionsKeepTheGeometricSeries) {
  const float Le = 1.0f, a = 0.5f;
  Scene scene = empty_scene({0.1f, 0.2f, 0.3f}, {0.1f, 0.2f, -1.0f}, {0, 1, 0}, 90.0f, 12, 12);
  add_box(scene, {-1, -1, -1}, {1, 1, 1}, add_material(scene, emissive(glm::vec3(Le), glm::vec3(a))), true);
  for (const auto& [splits, connections] : {std::pair{1u, 1u}, std::pair{4u, 1u}, std::pair{2u, 3u}})
    for (int k : {3, -1}) {
      RenderOptions o = path_options(48, k);
      o.settings.splits = splits;
      o.settings.light_connections = connections;
      const Rendered r = render_scene(scene, o);
      const double expected = k < 0 ? Le / (1.0 - a) : Le * (1.0 - std::pow(a, k)) / (1.0 - a);
      SCOPED_TRACE(::testing::Message() << "splits " << splits << ", light connections " << connections << ", max depth " << k);
      expect_region(r, 0, expected, all_pixels, "enclosure");
      EXPECT_EQ(r.stats.nonfinite_samples, 0u);
    }
}

// Irradiance at p from a uniform polygonal Lambertian emitter (Lambert's formula):
//   E = Le / 2 * sum_i angle(v_i, v_i+1) * (n . normalize(v_i x v_i+1)),  v_i = corner_i - p.
double polygon_irradiance(const std::vector<glm::dvec3>& corners, glm::dvec3 p, glm::dvec3 n, double Le) {
  double sum = 0.0;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const glm::dvec3 v0 = glm::normalize(corners[i] - p), v1 = glm::normalize(corners[(i + 1) % corners.size()] - p);
    const double angle = std::acos(std::clamp(glm::dot(v0, v1), -1.0, 1.0));
    sum += angle * glm::dot(n, glm::normalize(glm::cross(v0, v1)));
  }
  return 0.5 * Le * std::abs(sum);
}

TEST(IntegratorAnalytic, DiffusePlaneUnderSquareLightMatchesLambertsPolygonFormula) {
  const float albedo = 0.75f, Le = 5.0f;
  Scene scene = empty_scene({0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 40.0f, 1, 1);  // camera unused
  add_quad(scene, {-3, 0, 3}, {6, 0, 0}, {0, 0, -6}, add_material(scene, diffuse(glm::vec3(albedo))));
  // Square light 1 x 1 at height 1, centred over (0.3, 0.2), front (normal) facing down.
  const glm::vec3 c0(-0.2f, 1.0f, -0.3f);
  add_quad(scene, c0, {1, 0, 0}, {0, 0, 1}, add_material(scene, emissive(glm::vec3(Le))));
  ASSERT_LT(glm::cross(glm::vec3(1, 0, 0), glm::vec3(0, 0, 1)).y, 0.0f);

  const glm::dvec3 p(0.1, 0.0, 0.4);
  const std::vector<glm::dvec3> corners = {glm::dvec3(c0), glm::dvec3(c0) + glm::dvec3(0, 0, 1),
                                           glm::dvec3(c0) + glm::dvec3(1, 0, 1), glm::dvec3(c0) + glm::dvec3(1, 0, 0)};
  const double expected = albedo / std::numbers::pi * polygon_irradiance(corners, p, {0, 1, 0}, Le);

  const ScopedFlushDenormals ftz;
  const std::unique_ptr<Backend> backend = built_backend(scene);
  RenderOptions opt;
  const RenderSetup setup(scene, opt, backend->traits());
  const SceneContext ctx = SceneContext::make(scene, *backend, setup.environment(), setup.lights());
  // A ray from the side, below the light, onto p.
  Ray ray;
  ray.org = glm::vec3(2.5f, 0.3f, 0.4f);
  ray.dir = glm::normalize(glm::vec3(p) - ray.org);
  for (SamplingStrategy strategy : {SamplingStrategy::Mis, SamplingStrategy::Light, SamplingStrategy::Bsdf}) {
    for (IntegratorKind kind : {IntegratorKind::Path, IntegratorKind::Direct}) {
      IntegratorSettings settings;
      settings.strategy = strategy;
      const auto integrator = make_integrator(kind, ctx, settings);
      const int n = strategy == SamplingStrategy::Bsdf ? 200000 : 40000;
      double sum = 0.0, sum_sq = 0.0;
      TraceCounters counters;
      for (int i = 0; i < n; ++i) {
        // Independent samples: the standard error below assumes them.
        Sampler sampler(SamplerKind::Independent, 3, 0, static_cast<std::uint32_t>(i));
        const double v = integrator->radiance(ray, sampler, counters, nullptr).x;
        sum += v;
        sum_sq += v * v;
      }
      const double mean = sum / n;
      const double se = std::sqrt(std::max(0.0, sum_sq / n - mean * mean) / (n - 1));
      EXPECT_NEAR(mean, expected, kSigmas * se + 1e-6)
          << to_string(kind) << " " << to_string(strategy) << ", standard error " << se;
    }
  }
}

TEST(IntegratorAnalytic, GlassWithIorOneIsInvisibleAndCastsNoShadow) {
  const float a = 0.5f;
  const glm::vec3 L(1.0f);
  Scene scene = empty_scene({0, 3, 0}, {0, 0, 0}, {0, 0, -1}, 40.0f, 16, 16);
  constant_environment(scene, L);
  add_quad(scene, {-3, 0, 3}, {6, 0, 0}, {0, 0, -6}, add_material(scene, diffuse(glm::vec3(a))));
  add_sphere(scene, {0, 0.8f, 0}, 0.5f, add_material(scene, glass(1.0f)));
  const Rendered r = render_scene(scene, path_options(96));
  // The sphere covers the central pixels, and its "shadow" would fall right below it.
  auto centre = [](int x, int y) { return x >= 5 && x < 11 && y >= 5 && y < 11; };
  auto outside = [](int x, int y) { return x < 3 || x >= 13 || y < 3 || y >= 13; };
  expect_region(r, 0, a * L.x, centre, "seen through the glass sphere (and in its shadow)");
  expect_region(r, 0, a * L.x, outside, "plane away from the sphere");
}

// A faceted ior-4 sphere (critical angle 14.5 degrees) traps light in long total-internal-reflection
// chains whose throughput stays exactly 1; every chain leaves eventually, so the sphere is invisible in a
// uniform sky. This is the case where capping the roulette's survival at 0.95 for such paths made an
// infinite-variance estimator whose sample means sat ~1.6% low (russian_roulette.h).
TEST(IntegratorAnalytic, FacetedGlassWithTotalInternalReflectionIsInvisibleInUniformSky) {
  Scene scene = empty_scene({0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 40.0f, 32, 32);
  constant_environment(scene, glm::vec3(1.0f));
  TriangleMesh mesh = tessellated_sphere({0, 0, 0}, 1.0f, 3).meshes.front();
  mesh.geom_id = next_geom_id(scene);
  scene.geometry.meshes.push_back(std::move(mesh));
  scene.shapes.push_back({"mesh", ShapeKind::Mesh, add_material(scene, glass(4.0f)), {}});
  const Rendered r = render_scene(scene, path_options(64));
  expect_region(r, 0, 1.0, all_pixels, "ior-4 icosphere");
  EXPECT_EQ(r.stats.nonfinite_samples, 0u);
}

TEST(IntegratorAnalytic, MirrorSphereInUniformEnvironmentReflectsRTimesL) {
  const glm::vec3 L(1.5f, 1.0f, 0.5f), R(0.8f, 0.6f, 0.4f);
  Scene scene = empty_scene({0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 50.0f, 16, 16);
  constant_environment(scene, L);
  add_sphere(scene, {0, 0, 0}, 1.0f, add_material(scene, mirror(R)));
  const Rendered r = render_scene(scene, path_options(8));
  std::size_t checked = 0;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      if (std::abs(r.albedo.at(x, y, 0) - R.x) > 1e-6f) continue;
      ++checked;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.mean.at(x, y, c), R[c] * L[c], 1e-5) << x << "," << y;
    }
  EXPECT_GT(checked, 50u);
}

TEST(IntegratorAnalytic, WhitePlaneUnderHdrMapShowsIrradianceOverPi) {
  // A small synthetic map with a bright spot above the horizon and colour everywhere.
  const int W = 32, H = 16;
  Image map(W, H, 3);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      map.at(x, y, 0) = 0.2f + 0.05f * static_cast<float>(x % 5);
      map.at(x, y, 1) = 0.1f + 0.1f * static_cast<float>(y);
      map.at(x, y, 2) = 0.3f;
    }
  map.at(10, 4, 0) = map.at(10, 4, 1) = map.at(10, 4, 2) = 200.0f;
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "twinray_test_render_env";
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / "map.exr";
  write_exr(file, map);

  Scene scene = empty_scene({0, 3, 0}, {0, 0, 0}, {0, 0, -1}, 30.0f, 8, 8);
  scene.environment.type = EnvironmentType::Image;
  scene.environment.image = file;
  scene.environment.rotation_deg = 30.0f;
  add_quad(scene, {-3, 0, 3}, {6, 0, 0}, {0, 0, -6}, add_material(scene, diffuse(glm::vec3(1.0f))));
  const std::unique_ptr<EnvironmentLight> env = EnvironmentLight::create(scene.environment);
  const glm::dvec3 E = environment_irradiance(*env, {0, 1, 0});
  for (bool importance : {true, false}) {
    RenderOptions o = path_options(importance ? 128 : 512);
    o.env_importance_sampling = importance;
    const Rendered r = render_scene(scene, o);
    EXPECT_EQ(r.features.env_sampling_tables, importance);
    for (int c = 0; c < 3; ++c)
      expect_region(r, c, E[c] / std::numbers::pi, all_pixels, importance ? "importance" : "uniform");
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace twinray
