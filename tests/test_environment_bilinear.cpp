// EnvironmentLight with bilinear lookup (Environment::filter = Bilinear, Mitsuba 3's envmap convention):
// eval against a bilinear interpolation written here from the documented convention, the periodic seam
// and the poles, pdf normalisation over the documented patch grid, sample/pdf/eval consistency and the
// patch histogram, unbiasedness of importance-sampled irradiance against an independent 1D integral, and
// the map-size error.

#include "core/image/image_io.h"
#include "core/lights/environment_light.h"
#include "core/sampling/rng.h"
#include "core/util/input_error.h"

#include "tests/chi_square.h"
#include "tests/environment_test_util.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include <unistd.h>

namespace twinray {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;

// The documented direction convention: u = 0.5 + phi / 2pi with phi = atan2(x, -z), v = theta / pi.
glm::dvec3 bilinear_test_direction(double u, double v) {
  const double phi = 2.0 * kPi * (u - 0.5), theta = kPi * v;
  return glm::dvec3(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
}

// Mitsuba's lookup, written from its documentation of the grid: texel centres at u = (x + 0.5) / w
// (periodic) and v = y / (h - 1); plain bilinear weights between the four centres around (u, v).
glm::dvec3 bilinear_reference(const Image& map, double u, double v) {
  const int w = map.width, h = map.height;
  double fu = u * w - 0.5;
  fu -= w * std::floor(fu / w);
  const double fv = v * (h - 1);
  const int x0 = static_cast<int>(std::floor(fu)) % w, x1 = (x0 + 1) % w;
  const int y0 = std::min(static_cast<int>(std::floor(fv)), h - 2), y1 = y0 + 1;
  const double a = fu - std::floor(fu), b = fv - y0;
  glm::dvec3 out(0.0);
  for (int c = 0; c < 3; ++c)
    out[c] = (1 - a) * (1 - b) * map.at(x0, y0, c) + a * (1 - b) * map.at(x1, y0, c) + (1 - a) * b * map.at(x0, y1, c) +
             a * b * map.at(x1, y1, c);
  return out;
}

double bilinear_luminance(glm::dvec3 c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; }

// Solid angle of patch row y of a w-column grid with `rows` rows equal in theta.
double bilinear_patch_solid_angle(int y, int w, int rows) {
  return 2.0 * kPi / w * (std::cos(kPi * y / rows) - std::cos(kPi * (y + 1) / rows));
}

class EnvironmentBilinear : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("twinray-envbilinear-" + std::to_string(::getpid()) + "-" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::unique_ptr<EnvironmentLight> light_for(const Image& map, float rotation_deg = 0.0f, bool importance = true) {
    write_exr(dir_ / "map.exr", map);
    Environment env;
    env.type = EnvironmentType::Image;
    env.image = dir_ / "map.exr";
    env.rotation_deg = rotation_deg;
    env.filter = EnvironmentFilter::Bilinear;
    return EnvironmentLight::create(env, importance);
  }

  // 7 x 5 map, every texel distinct: (x + 1, y + 1, 0.25 (x + y) + 0.5).
  static Image labelled() {
    Image map(7, 5, 3);
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 7; ++x) {
        map.at(x, y, 0) = static_cast<float>(x + 1);
        map.at(x, y, 1) = static_cast<float>(y + 1);
        map.at(x, y, 2) = 0.25f * static_cast<float>(x + y) + 0.5f;
      }
    return map;
  }

  fs::path dir_;
};

TEST_F(EnvironmentBilinear, EvalIsMitsubasBilinearLookup) {
  const Image map = labelled();
  const auto light = light_for(map);
  ASSERT_EQ(light->filter(), EnvironmentFilter::Bilinear);
  EXPECT_EQ(light->cell_grid(), glm::ivec2(7, 4));
  // At texel centres the map's own values (float rounding of the direction round trip: 1e-4 relative).
  for (int y = 1; y < 4; ++y)
    for (int x = 0; x < 7; ++x) {
      const glm::vec3 got = light->eval(glm::vec3(bilinear_test_direction((x + 0.5) / 7.0, y / 4.0)));
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], map.at(x, y, c), 1e-4f * map.at(x, y, c)) << x << "," << y;
    }
  // The poles are rows 0 and 4 (green 1 and 5 whatever the column).
  EXPECT_NEAR(light->eval(glm::vec3(0, 1, 0)).g, 1.0f, 1e-6f);
  EXPECT_NEAR(light->eval(glm::vec3(0, -1, 0)).g, 5.0f, 1e-6f);
  // The seam: u = 0 lies half way between the last column (red 7) and the first (red 1).
  EXPECT_NEAR(light->eval(glm::vec3(bilinear_test_direction(1.0 - 1e-7, 0.5))).r, 4.0f, 1e-3f);
  EXPECT_NEAR(light->eval(glm::vec3(bilinear_test_direction(1e-7, 0.5))).r, 4.0f, 1e-3f);
  // Anywhere: the reference interpolation. Errors: the direction's float rounding moves (u, v) by a few
  // 1e-7, times the largest slope (6 per texel in red across the seam, 7 texels per unit u): < 1e-4.
  Rng rng(5, 8);
  for (int i = 0; i < 2000; ++i) {
    const double u = rng.next_float(), v = 0.01 + 0.98 * rng.next_float();
    const glm::vec3 got = light->eval(glm::vec3(bilinear_test_direction(u, v)));
    const glm::dvec3 want = bilinear_reference(map, u, v);
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(got[c], want[c], 1e-4 * std::max(1.0, want[c])) << "u " << u << " v " << v;
  }
}

TEST_F(EnvironmentBilinear, RotationTurnsTheLookupLikeTheNearestOne) {
  const Image map = labelled();
  const auto rotated = light_for(map, 90.0f);
  // Rotating by +90 degrees shows towards -Z what the unrotated map showed towards +X (u = 0.75).
  const glm::dvec3 want = bilinear_reference(map, 0.75, 0.5);
  const glm::vec3 got = rotated->eval(glm::vec3(0, 0, -1));
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 1e-4 * want[c]);
}

TEST_F(EnvironmentBilinear, PdfIsConstantPerPatchAndIntegratesToOne) {
  Image map = labelled();
  map.at(2, 1, 0) = 400.0f;  // a bright texel: the four patches around it get most of the weight
  for (int x = 0; x < 7; ++x)
    for (int c = 0; c < 3; ++c) map.at(x, 4, c) = map.at(x, 3, c) = 0.0f;  // the last patch row is black
  const auto light = light_for(map);
  const int w = 7, rows = 4, k = 6;
  double total = 0.0;
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < w; ++x) {
      // k x k sub-cells of the patch (equal in phi and cos theta): the pdf must not vary inside it.
      const double c0 = std::cos(kPi * y / rows), c1 = std::cos(kPi * (y + 1) / rows);
      float first = -1.0f;
      for (int j = 0; j < k; ++j)
        for (int i = 0; i < k; ++i) {
          const double u = (x + 0.5 + (i + 0.5) / k) / w;
          const double v = std::acos(c0 + (c1 - c0) * (j + 0.5) / k) / kPi;
          const float p = light->pdf(glm::vec3(bilinear_test_direction(u - std::floor(u), v)));
          if (first < 0.0f) first = p;
          ASSERT_EQ(p, first) << "patch " << x << "," << y;
        }
      if (y == rows - 1) EXPECT_EQ(first, 0.0f) << "a patch with four black corners has pdf 0";
      else EXPECT_GT(first, 0.0f);
      total += first * bilinear_patch_solid_angle(y, w, rows);
    }
  // Float pdfs summed in double: 1e-5 covers their rounding.
  EXPECT_NEAR(total, 1.0, 1e-5);
}

TEST_F(EnvironmentBilinear, SamplesAgreeWithPdfAndEvalAndFollowThePatchWeights) {
  Image map = labelled();
  map.at(5, 0, 1) = 300.0f;  // bright at the zenith row: patches touching the pole
  const auto light = light_for(map);
  const int w = 7, rows = 4;
  std::vector<double> weight(static_cast<std::size_t>(w * rows)), observed(weight.size(), 0.0), expected(weight.size());
  double weight_total = 0.0;
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < w; ++x) {
      const int x1 = (x + 1) % w;
      glm::dvec3 corners(0.0);
      for (int c = 0; c < 3; ++c)
        corners[c] = 0.25 * (map.at(x, y, c) + map.at(x1, y, c) + map.at(x, y + 1, c) + map.at(x1, y + 1, c));
      weight[static_cast<std::size_t>(y * w + x)] = bilinear_luminance(corners) * bilinear_patch_solid_angle(y, w, rows);
      weight_total += weight[static_cast<std::size_t>(y * w + x)];
    }
  const int n = 200000;
  Rng rng(21, 4);
  for (int i = 0; i < n; ++i) {
    const EnvironmentLight::Sample s = light->sample(glm::vec2(rng.next_float(), rng.next_float()));
    ASSERT_NEAR(glm::length(s.dir), 1.0f, 1e-5f);
    ASSERT_EQ(s.pdf, light->pdf(s.dir));
    ASSERT_EQ(s.radiance, light->eval(s.dir));
    ASSERT_GT(s.pdf, 0.0f);
    const glm::ivec2 cell = light->cell_of(s.dir);
    ASSERT_NEAR(s.pdf, weight[static_cast<std::size_t>(cell.y * w + cell.x)] / weight_total /
                           bilinear_patch_solid_angle(cell.y, w, rows),
                2e-6 * s.pdf);
    observed[static_cast<std::size_t>(cell.y * w + cell.x)] += 1.0;
  }
  for (std::size_t c = 0; c < weight.size(); ++c) expected[c] = n * weight[c] / weight_total;
  EXPECT_TRUE(twinray::testing::chi_square_accepts(observed, expected));
}

TEST_F(EnvironmentBilinear, IrradianceMatchesAnIndependentIntegralAndTheSampledEstimate) {
  // Rows 0..4 of a 9-row map are 1, rows 5..8 are 0. Texel rows sit at theta = y pi / 8, so the radiance
  // is 1 down to the horizon and falls linearly in theta to 0 at theta = 5 pi / 8.
  Image map(8, 9, 3);
  for (int y = 0; y <= 4; ++y)
    for (int x = 0; x < 8; ++x)
      for (int c = 0; c < 3; ++c) map.at(x, y, c) = 1.0f;
  const auto light = light_for(map, 17.0f);
  const auto radiance = [](double theta) {
    return theta <= kPi / 2 ? 1.0 : std::max(0.0, 1.0 - (theta - kPi / 2) / (kPi / 8));
  };
  // E(+-Y) = 2 pi * integral of L(theta) |cos theta| sin theta over the hemisphere, by Simpson's rule on
  // 20000 intervals (error far below 1e-9).
  const auto hemisphere = [&](double lo, double hi) {
    const int n = 20000;
    const double step = (hi - lo) / n;
    double sum = 0.0;
    for (int i = 0; i <= n; ++i) {
      const double t = lo + i * step;
      const double f = radiance(t) * std::abs(std::cos(t)) * std::sin(t);
      sum += f * (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0));
    }
    return 2.0 * kPi * sum * step / 3.0;
  };
  const double up = hemisphere(0.0, kPi / 2), down = hemisphere(kPi / 2, kPi);
  EXPECT_NEAR(up, kPi, 1e-9);
  // The quadrature's midpoint rule: exact for +Y (constant radiance, cosine linear in cos theta); on the
  // ramp seen from -Y its error is 0.8% at 8 subdivisions per patch row and falls as 1 / k^2, so 5e-4 at 32.
  EXPECT_NEAR(environment_irradiance(*light, glm::vec3(0, 1, 0), 8).x, up, 1e-9 * up);
  EXPECT_NEAR(environment_irradiance(*light, glm::vec3(0, -1, 0), 32).x, down, 1e-3 * down);

  // The light's own importance sampler, for a tilted normal: unbiased against the quadrature.
  const glm::vec3 n = glm::normalize(glm::vec3(0.3f, -0.6f, 0.5f));
  const double reference = environment_irradiance(*light, n, 16).x;
  const testing::SampledEstimate e = testing::sampled_red_irradiance(*light, n, 200000, Rng(9, 1));
  EXPECT_NEAR(e.mean, reference, 5.0 * e.std_error + 1e-3 * reference);
}

TEST_F(EnvironmentBilinear, AMapOneRowHighIsAnInputError) {
  Image map(4, 1, 3);
  for (float& f : map.data) f = 1.0f;
  try {
    light_for(map);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), dir_ / "map.exr");
    EXPECT_NE(std::string(e.what()).find("2 texels high"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace twinray
