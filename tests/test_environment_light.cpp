// EnvironmentLight: the lat-long direction convention (checked against directions built here from the
// documented formulas, not from the implementation), rotation, pdf normalisation by exact texel
// quadrature, sample/pdf/eval consistency, sampled histograms, the bright-texel probability, irradiance
// quadrature, input errors, and the shared studio HDR map.

#include "core/image/image_io.h"
#include "core/lights/environment_light.h"
#include "core/sampling/rng.h"
#include "core/util/input_error.h"

#include "tests/chi_square.h"
#include "tests/environment_test_util.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <unistd.h>

namespace twinray {
namespace {

using twinray::testing::chi_square_accepts;
namespace fs = std::filesystem;


// The documented convention, written out independently of the implementation: map column coordinate
// u = 0.5 + phi / 2pi with phi = atan2(x, -z); v = theta / pi with theta measured from +Y.
glm::dvec3 direction_from_map(double u, double cos_theta) {
  const double phi = 2.0 * std::numbers::pi * (u - 0.5);
  const double s = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
  return glm::dvec3(s * std::sin(phi), cos_theta, -s * std::cos(phi));
}
double texel_solid_angle(int y, int w, int h) {
  return 2.0 * std::numbers::pi / w * (std::cos(std::numbers::pi * y / h) - std::cos(std::numbers::pi * (y + 1) / h));
}
float luminance(glm::vec3 c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

class EnvironmentLightTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("twinray-env-" + std::to_string(::getpid()) + "-" + std::string(info->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes `img` as an EXR and returns the image environment for it.
  Environment image_environment(const Image& img, const std::string& name = "env.exr", float rotation_deg = 0.0f,
                                float scale = 1.0f) {
    write_exr(dir_ / name, img);
    Environment env;
    env.type = EnvironmentType::Image;
    env.image = dir_ / name;
    env.rotation_deg = rotation_deg;
    env.scale = scale;
    return env;
  }

  // 9 x 5 map whose texel (x, y) has radiance (x + 1, y + 1, 0.5): every texel distinct and non-zero.
  // Odd sizes put the horizon and the -Z/+X/-X directions at texel centres instead of on edges.
  static Image labelled_map() {
    Image img(9, 5, 3);
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 9; ++x) {
        img.at(x, y, 0) = static_cast<float>(x + 1);
        img.at(x, y, 1) = static_cast<float>(y + 1);
        img.at(x, y, 2) = 0.5f;
      }
    return img;
  }

  fs::path dir_;
};

glm::vec3 labelled(int x, int y) { return glm::vec3(static_cast<float>(x + 1), static_cast<float>(y + 1), 0.5f); }

TEST_F(EnvironmentLightTest, NoneGivesNoLight) { EXPECT_EQ(EnvironmentLight::create(Environment{}), nullptr); }

TEST_F(EnvironmentLightTest, EvalFollowsTheDocumentedConvention) {
  const auto light = EnvironmentLight::create(image_environment(labelled_map()));
  ASSERT_NE(light, nullptr);
  EXPECT_EQ(light->width(), 9);
  EXPECT_EQ(light->height(), 5);
  EXPECT_FALSE(light->is_constant());
  // Zenith: top row (any column is right at the pole); nadir: bottom row.
  EXPECT_EQ(light->eval(glm::vec3(0, 1, 0)).g, 1.0f);
  EXPECT_EQ(light->eval(glm::vec3(0, -1, 0)).g, 5.0f);
  // Horizon (row 2): -Z at the centre column 4, +X at u = 0.75 (column 6), -X at u = 0.25 (column 2),
  // +Z at the left/right edge (just left of +Z is column 8... seen from inside: x slightly > 0 gives u ~ 1).
  EXPECT_EQ(light->eval(glm::vec3(0, 0, -1)), labelled(4, 2));
  EXPECT_EQ(light->eval(glm::vec3(1, 0, 0)), labelled(6, 2));
  EXPECT_EQ(light->eval(glm::vec3(-1, 0, 0)), labelled(2, 2));
  EXPECT_EQ(light->eval(glm::normalize(glm::vec3(0.01f, 0, 1))), labelled(8, 2));
  EXPECT_EQ(light->eval(glm::normalize(glm::vec3(-0.01f, 0, 1))), labelled(0, 2));
  // Every texel centre, built from the documented formulas.
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 9; ++x) {
      const double cos_theta = std::cos(std::numbers::pi * (y + 0.5) / 5);
      const glm::vec3 d(direction_from_map((x + 0.5) / 9, cos_theta));
      EXPECT_EQ(light->eval(d), labelled(x, y)) << "texel " << x << ", " << y;
      EXPECT_EQ(light->texel_of(d), glm::ivec2(x, y));
    }
}

TEST_F(EnvironmentLightTest, RotationTurnsTheMapCounterClockwiseSeenFromAbove) {
  const Image map = labelled_map();
  const auto turned = EnvironmentLight::create(image_environment(map, "a.exr", 90.0f));
  // +90: what the unrotated map shows towards +X is seen towards -Z, -Z's moves to -X, -X's to +Z.
  EXPECT_EQ(turned->eval(glm::vec3(0, 0, -1)), labelled(6, 2));
  EXPECT_EQ(turned->eval(glm::vec3(-1, 0, 0)), labelled(4, 2));
  const auto back = EnvironmentLight::create(image_environment(map, "b.exr", -90.0f));
  EXPECT_EQ(back->eval(glm::vec3(0, 0, -1)), labelled(2, 2));
  const auto full = EnvironmentLight::create(image_environment(map, "c.exr", 360.0f));
  EXPECT_EQ(full->eval(glm::vec3(0, 0, -1)), labelled(4, 2));
  // Sampling follows the rotation: the pdf is proportional to the luminance of eval in every direction.
  const auto ratio = turned->pdf(glm::vec3(1, 0, 0)) / luminance(turned->eval(glm::vec3(1, 0, 0)));
  EXPECT_NEAR(turned->pdf(glm::vec3(0, 0, -1)) / luminance(turned->eval(glm::vec3(0, 0, -1))), ratio, 1e-5f * ratio);
}

TEST_F(EnvironmentLightTest, ScaleMultipliesRadiance) {
  const auto light = EnvironmentLight::create(image_environment(labelled_map(), "s.exr", 0.0f, 2.0f));
  EXPECT_EQ(light->eval(glm::vec3(0, 0, -1)), 2.0f * labelled(4, 2));
}

// Quadrature of pdf over the sphere on cells that subdivide each texel and are equal in solid angle
// (steps in phi and cos theta), so no cell straddles a texel edge and the piecewise-constant pdf is
// integrated exactly up to float rounding.
double integrate_pdf(const EnvironmentLight& light, int w, int h, int k) {
  double sum = 0.0;
  for (int y = 0; y < h; ++y) {
    const double c0 = std::cos(std::numbers::pi * y / h), c1 = std::cos(std::numbers::pi * (y + 1) / h);
    for (int j = 0; j < k; ++j) {
      const double z = c0 + (j + 0.5) / k * (c1 - c0);
      for (int i = 0; i < w * k; ++i) {
        const glm::vec3 d(direction_from_map((i + 0.5) / (w * k), z));
        sum += light.pdf(d) * (2.0 * std::numbers::pi / (w * k)) * (c0 - c1) / k;
      }
    }
  }
  return sum;
}

TEST_F(EnvironmentLightTest, PdfIntegratesToOneOverTheSphere) {
  Image map = labelled_map();
  map.at(3, 1, 0) = map.at(3, 1, 1) = map.at(3, 1, 2) = 0.0f;  // a black texel
  map.at(7, 0, 0) = 500.0f;                                       // a bright one next to the pole
  const Environment env = image_environment(map);
  const auto importance = EnvironmentLight::create(env, true);
  const auto uniform = EnvironmentLight::create(env, false);
  ASSERT_TRUE(importance->has_sampling_tables());
  EXPECT_FALSE(uniform->has_sampling_tables());
  // Float pdfs summed in double: 1e-5 covers their rounding and the float direction round trip.
  EXPECT_NEAR(integrate_pdf(*importance, 9, 5, 4), 1.0, 1e-5);
  EXPECT_NEAR(integrate_pdf(*uniform, 9, 5, 4), 1.0, 1e-5);
  // Black texel: pdf 0 there.
  EXPECT_EQ(importance->pdf(glm::vec3(direction_from_map(3.5 / 9, std::cos(std::numbers::pi * 1.5 / 5)))), 0.0f);
}

TEST_F(EnvironmentLightTest, SamplesAgreeWithPdfAndEvalAndFollowTheDistribution) {
  Image map = labelled_map();
  map.at(3, 1, 0) = map.at(3, 1, 1) = map.at(3, 1, 2) = 0.0f;
  map.at(7, 0, 0) = 500.0f;
  const auto light = EnvironmentLight::create(image_environment(map));
  double weight_total = 0.0;
  std::vector<double> weight(45);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 9; ++x) {
      const glm::vec3 c(map.at(x, y, 0), map.at(x, y, 1), map.at(x, y, 2));
      weight[static_cast<std::size_t>(y * 9 + x)] = luminance(c) * texel_solid_angle(y, 9, 5);
      weight_total += weight[static_cast<std::size_t>(y * 9 + x)];
    }
  const int n = 200000;
  std::vector<double> observed(45, 0.0), expected(45);
  Rng rng(12, 34);
  int invalid = 0;
  for (int i = 0; i < n; ++i) {
    const EnvironmentLight::Sample s = light->sample(glm::vec2(rng.next_float(), rng.next_float()));
    ASSERT_NEAR(glm::length(s.dir), 1.0f, 1e-5f);
    ASSERT_EQ(s.pdf, light->pdf(s.dir));
    ASSERT_EQ(s.radiance, light->eval(s.dir));
    if (s.pdf == 0.0f) {
      ++invalid;
      continue;
    }
    // Within a texel the solid-angle pdf is luminance / sum(luminance * solid angle): check it exactly.
    ASSERT_NEAR(s.pdf, luminance(s.radiance) / weight_total, 2e-6 * s.pdf);
    const glm::ivec2 t = light->texel_of(s.dir);
    observed[static_cast<std::size_t>(t.y * 9 + t.x)] += 1.0;
  }
  // A sample drawn next to the black texel's edge may round into it (measure zero in exact arithmetic).
  EXPECT_LE(invalid, 2);
  for (std::size_t k = 0; k < 45; ++k) expected[k] = n * weight[k] / weight_total;
  EXPECT_TRUE(chi_square_accepts(observed, expected));
}

TEST_F(EnvironmentLightTest, DirectionsInsideATexelAreUniformInSolidAngle) {
  // A single bright texel: all samples fall in it, and their cos(theta) must be uniform across the
  // texel's band (uniform in theta would over-sample the pole side).
  Image map(8, 4, 3);
  map.at(5, 0, 0) = map.at(5, 0, 1) = map.at(5, 0, 2) = 1.0f;
  const auto light = EnvironmentLight::create(image_environment(map));
  const double c0 = 1.0, c1 = std::cos(std::numbers::pi / 4);
  const int n = 50000, bins = 20;
  std::vector<double> observed(bins, 0.0), expected(bins, n / static_cast<double>(bins));
  Rng rng(8, 8);
  for (int i = 0; i < n; ++i) {
    const EnvironmentLight::Sample s = light->sample(glm::vec2(rng.next_float(), rng.next_float()));
    ASSERT_EQ(light->texel_of(s.dir), glm::ivec2(5, 0));
    const int b = std::clamp(static_cast<int>((c0 - s.dir.y) / (c0 - c1) * bins), 0, bins - 1);
    observed[static_cast<std::size_t>(b)] += 1.0;
    ASSERT_NEAR(s.pdf, 1.0 / texel_solid_angle(0, 8, 4), 1e-6 / texel_solid_angle(0, 8, 4));
  }
  EXPECT_TRUE(chi_square_accepts(observed, expected));
}

TEST_F(EnvironmentLightTest, OneBrightTexelIsSampledWithItsShareOfThePower) {
  Image map(64, 32, 3);
  std::fill(map.data.begin(), map.data.end(), 1.0f);
  const int bx = 40, by = 5;
  for (int c = 0; c < 3; ++c) map.at(bx, by, c) = 2000.0f;
  const auto light = EnvironmentLight::create(image_environment(map));
  const double bright = 2000.0 * texel_solid_angle(by, 64, 32);
  const double p = bright / (4.0 * std::numbers::pi - texel_solid_angle(by, 64, 32) + bright);  // ~0.44
  const int n = 100000;
  int hits = 0;
  Rng rng(21, 1);
  for (int i = 0; i < n; ++i)
    if (light->texel_of(light->sample(glm::vec2(rng.next_float(), rng.next_float())).dir) == glm::ivec2(bx, by)) ++hits;
  // Binomial: 5 standard deviations (~0.7% of p here) — a sampler that ignored the sin(theta) weight
  // would be off by ~50% for this row.
  const double sigma = std::sqrt(n * p * (1.0 - p));
  EXPECT_NEAR(hits, n * p, 5.0 * sigma);
  // Importance sampling against uniform: the pdf ratio at the bright texel is its luminance ratio to the mean.
  const auto uniform = EnvironmentLight::create(image_environment(map, "u.exr"), false);
  const glm::vec3 d(direction_from_map((bx + 0.5) / 64, std::cos(std::numbers::pi * (by + 0.5) / 32)));
  EXPECT_NEAR(light->pdf(d) / uniform->pdf(d), 2000.0 * 4.0 * std::numbers::pi / (4.0 * std::numbers::pi - texel_solid_angle(by, 64, 32) + bright),
              1e-4 * light->pdf(d) / uniform->pdf(d));
}

TEST_F(EnvironmentLightTest, ConstantEnvironmentHasNoTables) {
  Environment env;
  env.type = EnvironmentType::Constant;
  env.radiance = glm::vec3(0.5f, 1.0f, 2.0f);
  const auto light = EnvironmentLight::create(env, true);
  ASSERT_NE(light, nullptr);
  EXPECT_TRUE(light->is_constant());
  EXPECT_FALSE(light->has_sampling_tables());
  EXPECT_EQ(light->width(), 0);
  EXPECT_EQ(light->height(), 0);
  EXPECT_LT(light->memory_bytes(), 1024u);
  EXPECT_EQ(light->eval(glm::vec3(0.6f, 0.8f, 0.0f)), env.radiance);
  EXPECT_EQ(light->average_radiance(), env.radiance);
  const EnvironmentLight::Sample s = light->sample(glm::vec2(0.3f, 0.9f));
  EXPECT_FLOAT_EQ(s.pdf, static_cast<float>(1.0 / (4.0 * std::numbers::pi)));
  EXPECT_EQ(s.radiance, env.radiance);
}

TEST_F(EnvironmentLightTest, IrradianceOfAConstantEnvironmentIsPiL) {
  Environment env;
  env.type = EnvironmentType::Constant;
  env.radiance = glm::vec3(1.0f, 2.0f, 0.25f);
  const auto light = EnvironmentLight::create(env);
  // n = +-Y: the horizon is a row edge and the cosine is linear in the quadrature variable: exact.
  for (glm::vec3 n : {glm::vec3(0, 1, 0), glm::vec3(0, -1, 0)}) {
    const glm::dvec3 e = environment_irradiance(*light, n);
    EXPECT_NEAR(e.x, std::numbers::pi * 1.0, 1e-12);
    EXPECT_NEAR(e.y, std::numbers::pi * 2.0, 1e-12);
    EXPECT_NEAR(e.z, std::numbers::pi * 0.25, 1e-12);
  }
  // Tilted normals: the horizon cuts cells; the midpoint rule then errs by O(cell size^2) along it.
  // Measured error at subdivisions 4 on the 64 x 32 grid is below 1e-4 relative; 5e-4 is the bound.
  for (glm::vec3 n : {glm::vec3(1, 0, 0), glm::normalize(glm::vec3(0.3f, 0.5f, -0.8f))}) {
    const glm::dvec3 e = environment_irradiance(*light, n);
    EXPECT_NEAR(e.y / (std::numbers::pi * 2.0), 1.0, 5e-4);
  }
}

TEST_F(EnvironmentLightTest, IrradianceOfAnImageMap) {
  // Upper half 1, lower half 0 (even height: the horizon is a row edge): E(+Y) = pi, E(-Y) = 0, and a
  // horizontal normal sees exactly a quarter sphere of radiance 1 weighted by cos: E = 2 * (pi / 4) = pi / 2.
  Image map(16, 8, 3);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 16; ++x)
      for (int c = 0; c < 3; ++c) map.at(x, y, c) = 1.0f;
  const auto light = EnvironmentLight::create(image_environment(map));
  EXPECT_NEAR(environment_irradiance(*light, glm::vec3(0, 1, 0)).x, std::numbers::pi, 1e-12);
  EXPECT_NEAR(environment_irradiance(*light, glm::vec3(0, -1, 0)).x, 0.0, 1e-12);
  EXPECT_NEAR(environment_irradiance(*light, glm::vec3(1, 0, 0), 8).x, std::numbers::pi / 2.0, 2e-3);
  EXPECT_NEAR(light->average_radiance().x, 0.5f, 1e-6f);
}

TEST_F(EnvironmentLightTest, IrradianceAgreesWithImportanceSampledEstimate) {
  // Independent check of both: Monte Carlo E(n) = mean of L cos / pdf with the light's own sampler.
  Image map = labelled_map();
  map.at(7, 1, 0) = 300.0f;
  const auto light = EnvironmentLight::create(image_environment(map, "m.exr", 30.0f));
  const glm::vec3 n = glm::normalize(glm::vec3(0.2f, 0.7f, -0.4f));
  const glm::dvec3 reference = environment_irradiance(*light, n, 8);
  const testing::SampledEstimate e = testing::sampled_red_irradiance(*light, n, 200000, Rng(3, 3));
  // 5 standard errors, plus the quadrature's own error along the horizon (< 1e-3 relative at 8 subdivisions).
  EXPECT_NEAR(e.mean, reference.x, 5.0 * e.std_error + 1e-3 * reference.x);
}

TEST_F(EnvironmentLightTest, BadInputsThrowInputErrorNamingFileAndTexel) {
  Environment missing;
  missing.type = EnvironmentType::Image;
  missing.image = dir_ / "missing.hdr";
  try {
    EnvironmentLight::create(missing);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), missing.image);
  }

  std::ofstream(dir_ / "text.exr") << "not an image";
  Environment text = missing;
  text.image = dir_ / "text.exr";
  EXPECT_THROW(EnvironmentLight::create(text), InputError);

  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -1.0f}) {
    Image map = labelled_map();
    map.at(3, 1, 2) = bad;
    const Environment env = image_environment(map, "bad.exr");
    try {
      EnvironmentLight::create(env);
      FAIL() << "expected InputError for " << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), env.image);
      EXPECT_EQ(e.where(), "texel (3, 1)");
    }
  }

  Environment negative_constant;
  negative_constant.type = EnvironmentType::Constant;
  negative_constant.radiance = glm::vec3(1.0f, -1.0f, 1.0f);
  EXPECT_THROW(EnvironmentLight::create(negative_constant), InputError);
}

TEST(EnvironmentLightShared, StudioMapSamplesItsSmallBrightLamps) {
  const char* shared = std::getenv("TWINRAY_SHARED");
  if (!shared) GTEST_SKIP() << "TWINRAY_SHARED is not set: skipping the shared studio HDR map test";
  const fs::path file = fs::path(shared) / "data" / "envmaps" / "studio_small_03_1k.hdr";
  if (!fs::exists(file)) GTEST_SKIP() << file << " does not exist";
  Environment env;
  env.type = EnvironmentType::Image;
  env.image = file;
  const auto light = EnvironmentLight::create(env);
  ASSERT_EQ(light->width(), 1024);
  ASSERT_EQ(light->height(), 512);
  ASSERT_TRUE(light->has_sampling_tables());

  // The "lamps": the brightest texels that together cover 0.5% of the sphere. Measure their share of the
  // luminous power from the texels directly, then check that sampling hits them with that probability.
  const int w = 1024, h = 512;
  std::vector<std::pair<float, int>> by_luminance;
  double total = 0.0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double power = luminance(light->texel(x, y)) * texel_solid_angle(y, w, h);
      total += power;
      by_luminance.emplace_back(luminance(light->texel(x, y)), y * w + x);
    }
  std::sort(by_luminance.begin(), by_luminance.end(), std::greater<>());
  std::vector<char> is_lamp(static_cast<std::size_t>(w * h), 0);
  double lamp_solid_angle = 0.0, lamp_power = 0.0;
  for (const auto& [lum, index] : by_luminance) {
    if (lamp_solid_angle >= 0.005 * 4.0 * std::numbers::pi) break;
    const double sa = texel_solid_angle(index / w, w, h);
    lamp_solid_angle += sa;
    lamp_power += lum * sa;
    is_lamp[static_cast<std::size_t>(index)] = 1;
  }
  const double p = lamp_power / total;
  ASSERT_GT(p, 0.3) << "the studio map's lamps should dominate its power";  // a property of the data
  const int n = 100000;
  int hits = 0;
  Rng rng(77, 7);
  for (int i = 0; i < n; ++i) {
    const EnvironmentLight::Sample s = light->sample(glm::vec2(rng.next_float(), rng.next_float()));
    ASSERT_GT(s.pdf, 0.0f);
    const glm::ivec2 t = light->texel_of(s.dir);
    hits += is_lamp[static_cast<std::size_t>(t.y * w + t.x)];
  }
  EXPECT_NEAR(hits, n * p, 5.0 * std::sqrt(n * p * (1.0 - p)) + 1e-4 * n)  // 5 sigma + edge rounding slack
      << "lamps cover " << lamp_solid_angle / (4.0 * std::numbers::pi) << " of the sphere and hold " << p << " of the power";
  EXPECT_GT(light->memory_bytes(), static_cast<std::size_t>(w * h) * 12u);
}

}  // namespace
}  // namespace twinray
