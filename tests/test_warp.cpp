// Sampling warps: densities integrate to 1, samples follow the densities (Pearson chi-square on bins of
// known probability), the shading frame is orthonormal everywhere, the MIS weight survives extreme pdfs.

#include "core/sampling/rng.h"
#include "core/sampling/warp.h"

#include "tests/chi_square.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace twinray {
namespace {

using twinray::testing::chi_square_accepts;



// Histogram of sample directions on a (cos theta, phi) grid about +Z; cells are equal in solid angle
// (dw = dcos dphi). expected_prob(z0, z1) is the probability of the band z0 <= z < z1 (the densities below
// do not depend on phi, so each cell of the band gets 1 / phi_bins of it).
void check_direction_histogram(const std::function<glm::vec3(glm::vec2)>& warp,
                               const std::function<double(double, double)>& band_probability, double z_min,
                               int z_bins, int phi_bins, int samples) {
  std::vector<double> observed(static_cast<std::size_t>(z_bins * phi_bins), 0.0);
  std::vector<double> expected(observed.size(), 0.0);
  Rng rng(7, 11);
  for (int i = 0; i < samples; ++i) {
    const glm::vec3 d = warp(glm::vec2(rng.next_float(), rng.next_float()));
    ASSERT_NEAR(glm::length(d), 1.0f, 1e-5f);
    const double zt = (d.z - z_min) / (1.0 - z_min);
    const double pt = (std::atan2(d.y, d.x) + std::numbers::pi) / (2.0 * std::numbers::pi);
    const int zi = std::clamp(static_cast<int>(zt * z_bins), 0, z_bins - 1);
    const int pi = std::clamp(static_cast<int>(pt * phi_bins), 0, phi_bins - 1);
    observed[static_cast<std::size_t>(zi * phi_bins + pi)] += 1.0;
  }
  for (int zi = 0; zi < z_bins; ++zi) {
    const double z0 = z_min + (1.0 - z_min) * zi / z_bins, z1 = z_min + (1.0 - z_min) * (zi + 1) / z_bins;
    for (int pi = 0; pi < phi_bins; ++pi)
      expected[static_cast<std::size_t>(zi * phi_bins + pi)] = samples * band_probability(z0, z1) / phi_bins;
  }
  EXPECT_TRUE(chi_square_accepts(observed, expected));
}

// Midpoint quadrature of a density that depends only on cos(theta), over the band z_min..1 (dw = 2 pi dz).
double integrate_over_band(const std::function<double(double)>& pdf_of_z, double z_min, int steps) {
  double sum = 0.0;
  const double dz = (1.0 - z_min) / steps;
  for (int i = 0; i < steps; ++i) sum += pdf_of_z(z_min + (i + 0.5) * dz) * 2.0 * std::numbers::pi * dz;
  return sum;
}

TEST(Warp, CosineHemispherePdfIntegratesToOne) {
  // Midpoint rule is exact for the linear density cos/pi; tolerance is float rounding of the pdf.
  EXPECT_NEAR(integrate_over_band([](double z) { return cosine_hemisphere_pdf(static_cast<float>(z)); }, -1.0, 2000),
              1.0, 1e-6);
  EXPECT_EQ(cosine_hemisphere_pdf(-0.5f), 0.0f);
}

TEST(Warp, CosineHemisphereSamplesFollowPdf) {
  check_direction_histogram(sample_cosine_hemisphere, [](double z0, double z1) { return z1 * z1 - z0 * z0; }, 0.0,
                            16, 24, 400000);
}

TEST(Warp, CosineHemisphereStaysOnUpperHemisphere) {
  for (float a : {0.0f, 0.5f, 0x1.fffffep-1f})
    for (float b : {0.0f, 0.5f, 0x1.fffffep-1f}) {
      const glm::vec3 d = sample_cosine_hemisphere(glm::vec2(a, b));
      EXPECT_GE(d.z, 0.0f);
      EXPECT_NEAR(glm::length(d), 1.0f, 1e-6f);
    }
}

TEST(Warp, UniformSpherePdfIntegratesToOneAndSamplesFollowIt) {
  EXPECT_NEAR(integrate_over_band([](double) { return uniform_sphere_pdf(); }, -1.0, 10), 1.0, 1e-6);
  check_direction_histogram(sample_uniform_sphere, [](double z0, double z1) { return (z1 - z0) / 2.0; }, -1.0, 16,
                            24, 400000);
}

TEST(Warp, ConeSamplesStayInsideAndFollowPdf) {
  const float cos_max = 0.8f;
  const double one_minus = 1.0 - static_cast<double>(cos_max);
  EXPECT_NEAR(integrate_over_band([&](double) { return uniform_cone_pdf(cos_max); }, cos_max, 10), 1.0, 1e-6);
  check_direction_histogram([&](glm::vec2 u) { return sample_uniform_cone(u, cos_max); },
                            [&](double z0, double z1) { return (z1 - z0) / one_minus; }, cos_max, 10, 16, 200000);
}

TEST(Warp, TinyConeKeepsItsSizeWhereCosineRoundsToOne) {
  // A light of angular radius 1e-5 rad: cos(theta_max) = 1 - 5e-11 rounds to exactly 1 in float, so the
  // cos form degenerates (documented: pdf 0, all samples on the axis). The sin^2 / one-minus-cos form keeps
  // the cone: its pdf matches 1 / (2 pi (1 - cos)) to float precision and samples fill the cone out to its rim.
  const double radius = 1e-5;
  const float sin2 = static_cast<float>(radius * radius);
  ASSERT_EQ(std::sqrt(1.0f - sin2), 1.0f);
  EXPECT_EQ(uniform_cone_pdf(std::sqrt(1.0f - sin2)), 0.0f);

  const float omc = one_minus_cos_from_sin2(sin2);
  const double exact_omc = 1.0 - std::cos(std::asin(radius));  // ~ radius^2 / 2; double is ample here
  EXPECT_NEAR(omc / exact_omc, 1.0, 1e-6);
  EXPECT_NEAR(uniform_cone_pdf_one_minus_cos(omc) * (2.0 * std::numbers::pi * exact_omc), 1.0, 1e-6);

  Rng rng(3, 4);
  double max_sin = 0.0, mean_sin2 = 0.0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const glm::vec3 d = sample_uniform_cone_one_minus_cos(glm::vec2(rng.next_float(), rng.next_float()), omc);
    const double s = std::hypot(static_cast<double>(d.x), static_cast<double>(d.y));
    max_sin = std::max(max_sin, s);
    mean_sin2 += s * s / n;
  }
  EXPECT_LE(max_sin, radius * (1.0 + 1e-6));
  EXPECT_GE(max_sin, radius * 0.999);  // some sample lands near the rim
  // sin^2 is uniform on [0, radius^2] to first order: mean radius^2 / 2; 20000 samples give ~0.4% std error.
  EXPECT_NEAR(mean_sin2 / (radius * radius), 0.5, 0.02);
}

TEST(Warp, TriangleBarycentricsAreUniform) {
  // Histogram over (b0, b1) on an n x n grid of the unit square. The triangle b0 + b1 <= 1 covers cells
  // with i + j <= n - 2 fully and those with i + j = n - 1 exactly half (the diagonal cuts them); the
  // density on it is 2 (area 1/2).
  const int n = 16, samples = 300000;
  std::vector<double> observed(n * n, 0.0), expected(n * n, 0.0);
  Rng rng(5, 6);
  for (int s = 0; s < samples; ++s) {
    const glm::vec3 b = sample_uniform_triangle(glm::vec2(rng.next_float(), rng.next_float()));
    ASSERT_GE(b.x, 0.0f);
    ASSERT_GE(b.y, 0.0f);
    ASSERT_GE(b.z, 0.0f);
    ASSERT_EQ(b.z, 1.0f - b.x - b.y);  // formed as the complement, so the float sum is 1 to an ulp
    ASSERT_NEAR(b.x + b.y + b.z, 1.0f, 1.2e-7f);
    const int i = std::min(static_cast<int>(b.x * n), n - 1), j = std::min(static_cast<int>(b.y * n), n - 1);
    observed[static_cast<std::size_t>(i * n + j)] += 1.0;
  }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double area = i + j <= n - 2 ? 1.0 : (i + j == n - 1 ? 0.5 : 0.0);
      expected[static_cast<std::size_t>(i * n + j)] = samples * 2.0 * area / (n * n);
    }
  EXPECT_TRUE(chi_square_accepts(observed, expected));
}

void expect_orthonormal_frame(glm::vec3 n) {
  const Frame f = Frame::from_normal(n);
  SCOPED_TRACE(::testing::Message() << "n = (" << n.x << ", " << n.y << ", " << n.z << ")");
  EXPECT_NEAR(glm::length(f.s), 1.0f, 2e-6f);
  EXPECT_NEAR(glm::length(f.t), 1.0f, 2e-6f);
  EXPECT_NEAR(glm::dot(f.s, f.t), 0.0f, 2e-6f);
  EXPECT_NEAR(glm::dot(f.s, f.n), 0.0f, 2e-6f);
  EXPECT_NEAR(glm::dot(f.t, f.n), 0.0f, 2e-6f);
  const glm::vec3 c = glm::cross(f.s, f.t);  // right-handed
  EXPECT_NEAR(glm::distance(c, n), 0.0f, 4e-6f);
  const glm::vec3 v(0.3f, -0.5f, 0.8f);
  EXPECT_NEAR(glm::distance(f.to_world(f.to_local(v)), v), 0.0f, 4e-6f);
  EXPECT_NEAR(f.to_local(n).z, 1.0f, 2e-6f);
}

TEST(Frame, OrthonormalForAxesAndTheSingularCaseOfFrisvad) {
  for (glm::vec3 n : {glm::vec3(0, 0, 1), glm::vec3(0, 0, -1), glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0),
                      glm::vec3(0, 1, 0), glm::vec3(0, -1, 0), glm::normalize(glm::vec3(1e-4f, -2e-4f, -1.0f)),
                      glm::normalize(glm::vec3(1e-7f, 0.0f, -1.0f))})
    expect_orthonormal_frame(n);
  // -0 for z must pick the same branch consistently (copysign sees the sign bit).
  expect_orthonormal_frame(glm::vec3(1.0f, 0.0f, -0.0f));
}

TEST(Frame, OrthonormalForRandomNormals) {
  Rng rng(1, 2);
  for (int i = 0; i < 10000; ++i) expect_orthonormal_frame(sample_uniform_sphere(glm::vec2(rng.next_float(), rng.next_float())));
}

TEST(PowerHeuristic, ValuesAndExtremes) {
  EXPECT_FLOAT_EQ(power_heuristic(1, 1.0f, 1, 1.0f), 0.5f);
  EXPECT_FLOAT_EQ(power_heuristic(1, 2.0f, 1, 1.0f), 0.8f);
  EXPECT_FLOAT_EQ(power_heuristic(2, 1.0f, 1, 1.0f), 0.8f);
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_EQ(power_heuristic(1, inf, 1, 3.0f), 1.0f);  // delta distribution
  EXPECT_EQ(power_heuristic(1, 3.0f, 1, inf), 0.0f);
  EXPECT_EQ(power_heuristic(1, inf, 1, inf), 0.5f);
  EXPECT_EQ(power_heuristic(1, 0.0f, 1, 3.0f), 0.0f);
  EXPECT_EQ(power_heuristic(1, 0.0f, 1, 0.0f), 0.0f);
  EXPECT_EQ(power_heuristic(1, 3.0f, 1, 0.0f), 1.0f);
  // Squares that overflow or underflow in float must not produce NaN.
  EXPECT_FLOAT_EQ(power_heuristic(1, 1e30f, 1, 1e30f), 0.5f);
  EXPECT_FLOAT_EQ(power_heuristic(1, 1e-30f, 1, 1e-30f), 0.5f);
  EXPECT_EQ(power_heuristic(1, 1e30f, 1, 1e-30f), 1.0f);
  EXPECT_EQ(power_heuristic(1, 1e-30f, 1, 1e30f), 0.0f);
  // The two strategies' weights sum to 1.
  for (float a : {1e-20f, 0.1f, 1.0f, 7.0f, 1e20f})
    for (float b : {1e-20f, 0.1f, 1.0f, 7.0f, 1e20f})
      EXPECT_NEAR(power_heuristic(1, a, 1, b) + power_heuristic(1, b, 1, a), 1.0f, 1e-6f);
}

}  // namespace
}  // namespace twinray
