// Light sampling: each strategy's density integrates to the solid angle it covers, sample() and the pdf
// functions agree (MIS depends on it), and lights are chosen in proportion to their power.

#include "render_test_util.h"

#include "core/lights/area_lights.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace twinray {
namespace {

using namespace twinray::test;

// Solid angle of triangle (a, b, c) seen from the origin (Van Oosterom and Strackee).
double triangle_solid_angle(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
  const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
  const double num = std::abs(glm::dot(a, glm::cross(b, c)));
  const double den = la * lb * lc + glm::dot(a, b) * lc + glm::dot(a, c) * lb + glm::dot(b, c) * la;
  double omega = 2.0 * std::atan2(num, den);
  if (omega < 0.0) omega += 2.0 * std::numbers::pi;
  return omega;
}

Hit hit_for(std::uint32_t geom_id, std::uint32_t prim_id, glm::vec3 ng) {
  Hit h;
  h.geom_id = geom_id;
  h.prim_id = prim_id;
  h.ng = ng;
  h.t = 1.0f;
  return h;
}

TEST(AreaLights, TriangleSamplingIntegratesToItsSolidAngleAndMatchesPdf) {
  Scene scene;
  const glm::vec3 p0(-0.5f, 2.0f, -0.2f), p1(0.7f, 2.2f, 0.1f), p2(0.1f, 1.8f, 0.9f);
  // Counter-clockwise seen from below: the front faces the reference points under it.
  add_triangles(scene, {p0, p1, p2}, add_material(scene, emissive(glm::vec3(2.0f))));
  const LightSampler lights(scene, nullptr);
  ASSERT_EQ(lights.triangle_count(), 1u);
  ASSERT_LT(lights.triangles()[0].normal.y, 0.0f);

  for (const glm::vec3 ref : {glm::vec3(0, 0, 0), glm::vec3(0.3f, 1.5f, 0.2f), glm::vec3(-2.0f, 0.5f, 3.0f)}) {
    const double omega = triangle_solid_angle(glm::dvec3(p0 - ref), glm::dvec3(p1 - ref), glm::dvec3(p2 - ref));
    Rng rng(1, 4);
    constexpr int n = 200000;
    double sum = 0.0, sum_sq = 0.0;
    for (int i = 0; i < n; ++i) {
      const auto s = lights.sample(ref, rng.next_float(), {rng.next_float(), rng.next_float()});
      ASSERT_TRUE(s.has_value());
      EXPECT_EQ(s->radiance, glm::vec3(2.0f));
      EXPECT_NEAR(glm::dot(s->wi, glm::normalize(s->point - ref)), 1.0f, 1e-5f);
      const float pdf = lights.pdf_surface(ref, hit_for(0, 0, s->normal), s->point);
      EXPECT_NEAR(pdf, s->pdf, 1e-4f * s->pdf);
      const double w = 1.0 / s->pdf;
      sum += w;
      sum_sq += w * w;
    }
    const double mean = sum / n, se = std::sqrt((sum_sq / n - mean * mean) / (n - 1));
    EXPECT_NEAR(mean, omega, 4.0 * se + 1e-7) << "solid angle from (" << ref.x << "," << ref.y << "," << ref.z << ")";
  }
}

TEST(AreaLights, EmissionIsOneSided) {
  Material m = emissive(glm::vec3(3.0f));
  EXPECT_EQ(emitted_radiance(m, {0, 1, 0}, glm::normalize(glm::vec3(0.1f, 1, 0))), glm::vec3(3.0f));
  EXPECT_EQ(emitted_radiance(m, {0, 1, 0}, glm::normalize(glm::vec3(0.1f, -1, 0))), glm::vec3(0.0f));
  EXPECT_EQ(emitted_radiance(diffuse(glm::vec3(1.0f)), {0, 1, 0}, {0, 1, 0}), glm::vec3(0.0f));
}

TEST(AreaLights, SphereSeenFromOutsideIsSampledUniformlyInItsCone) {
  Scene scene;
  const glm::vec3 c(0.5f, 1.0f, -3.0f);
  const float r = 0.75f;
  add_sphere(scene, c, r, add_material(scene, emissive(glm::vec3(1.0f, 2.0f, 3.0f))));
  const LightSampler lights(scene, nullptr);
  ASSERT_EQ(lights.sphere_count(), 1u);
  for (const glm::vec3 ref : {glm::vec3(0.0f), glm::vec3(0.5f, 1.0f, -2.0f), glm::vec3(0.5f, 1.0f, -3.8f)}) {
    const double d = glm::length(glm::dvec3(c - ref));
    const double cos_max = std::sqrt(1.0 - (r / d) * (r / d));
    const double omega = 2.0 * std::numbers::pi * (1.0 - cos_max);
    Rng rng(8, 1);
    constexpr int n = 50000;
    double cos_sum = 0.0;
    for (int i = 0; i < n; ++i) {
      const auto s = lights.sample(ref, rng.next_float(), {rng.next_float(), rng.next_float()});
      ASSERT_TRUE(s.has_value());
      ASSERT_NEAR(1.0 / s->pdf, omega, 1e-4 * omega);
      EXPECT_NEAR(glm::length(s->point - c), r, 1e-5f * d);
      EXPECT_GT(glm::dot(s->normal, ref - s->point), 0.0f) << "sampled the far side";
      EXPECT_EQ(s->radiance, glm::vec3(1.0f, 2.0f, 3.0f));
      EXPECT_NEAR(lights.pdf_surface(ref, hit_for(0, 0, s->normal), s->point), s->pdf, 1e-4f * s->pdf);
      cos_sum += glm::dot(glm::dvec3(s->wi), glm::normalize(glm::dvec3(c - ref)));
    }
    // Uniform in the cone: E[cos] = (1 + cos_max) / 2, variance (1 - cos_max)^2 / 12.
    const double se = (1.0 - cos_max) / std::sqrt(12.0 * n);
    EXPECT_NEAR(cos_sum / n, 0.5 * (1.0 + cos_max), 4.0 * se);
  }
}

TEST(AreaLights, SphereSeenFromInsideIsSampledByAreaAndEmitsNothingInward) {
  Scene scene;
  add_sphere(scene, {0, 0, 0}, 2.0f, add_material(scene, emissive(glm::vec3(1.0f))));
  const LightSampler lights(scene, nullptr);
  const glm::vec3 ref(0.3f, -0.5f, 0.2f);
  Rng rng(2, 2);
  double sum = 0.0;
  constexpr int n = 100000;
  for (int i = 0; i < n; ++i) {
    const auto s = lights.sample(ref, rng.next_float(), {rng.next_float(), rng.next_float()});
    ASSERT_TRUE(s.has_value());
    EXPECT_EQ(s->radiance, glm::vec3(0.0f)) << "outward-only emission seen from inside";
    EXPECT_NEAR(lights.pdf_surface(ref, hit_for(0, 0, s->normal), s->point), s->pdf, 1e-4f * s->pdf);
    sum += 1.0 / s->pdf;
  }
  // Area sampling from inside covers the whole sphere of directions once.
  EXPECT_NEAR(sum / n, 4.0 * std::numbers::pi, 0.05);
}

TEST(AreaLights, LightsAreChosenInProportionToPower) {
  Scene scene;
  const std::uint32_t dim = add_material(scene, emissive(glm::vec3(1.0f)));
  const std::uint32_t bright = add_material(scene, emissive(glm::vec3(2.0f)));
  add_quad(scene, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}, dim);     // area 1 in two triangles
  add_quad(scene, {0, 5, 0}, {3, 0, 0}, {0, 0, 1}, bright);  // area 3
  add_sphere(scene, {4, 0, 0}, 0.5f, bright);                // area pi
  add_quad(scene, {9, 0, 0}, {1, 0, 0}, {0, 0, 1}, add_material(scene, diffuse(glm::vec3(1.0f))));  // not a light
  const LightSampler lights(scene, nullptr);
  ASSERT_EQ(lights.triangle_count(), 4u);
  ASSERT_EQ(lights.sphere_count(), 1u);
  // power ~ area * luminance(radiance); luminance is linear, so the ratios are those of area * scale.
  const double p[5] = {0.5, 0.5, 3.0, 3.0, 2.0 * std::numbers::pi * 0.25 * 4.0};
  const double total = p[0] + p[1] + p[2] + p[3] + p[4];
  for (std::size_t i = 0; i < 5; ++i) EXPECT_NEAR(lights.selection_probability(i), p[i] / total, 1e-6) << i;
}

TEST(AreaLights, EnvironmentJoinsTheSamplerAndItsPdfIncludesSelection) {
  Scene scene;
  add_quad(scene, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}, add_material(scene, emissive(glm::vec3(1.0f))));
  Environment env;
  env.type = EnvironmentType::Constant;
  env.radiance = glm::vec3(0.5f);
  const auto light = EnvironmentLight::create(env);
  const LightSampler lights(scene, light.get());
  ASSERT_TRUE(lights.has_environment());
  const float p_env = lights.selection_probability(2);
  EXPECT_GT(p_env, 0.0f);
  EXPECT_NEAR(lights.selection_probability(0) + lights.selection_probability(1) + p_env, 1.0f, 1e-6f);
  EXPECT_NEAR(lights.pdf_environment({0, 1, 0}), p_env / (4.0f * kPi), 1e-7f);
  Rng rng(4, 4);
  int env_samples = 0;
  constexpr int n = 20000;
  for (int i = 0; i < n; ++i) {
    const auto s = lights.sample({0.2f, -1.0f, 0.3f}, rng.next_float(), {rng.next_float(), rng.next_float()});
    if (s && s->is_environment) {
      ++env_samples;
      EXPECT_NEAR(s->pdf, lights.pdf_environment(s->wi), 1e-6f);
    }
  }
  EXPECT_NEAR(static_cast<double>(env_samples) / n, p_env, 4.0 * std::sqrt(p_env * (1 - p_env) / n));
}

}  // namespace
}  // namespace twinray
