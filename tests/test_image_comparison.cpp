// The statistics of `twinray compare` (harness/compare/image_comparison.h) on synthetic noisy images whose
// truth and noise are known: agreement within noise, planted differences found where they were planted,
// channel means with their standard errors, relMSE against a reference and from noise.

#include "harness/compare/image_comparison.h"

#include "core/sampling/rng.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace twinray::compare {
namespace {

// A gradient image plus Gaussian noise of standard deviation sigma per pixel (Box-Muller from PCG32),
// with the variance image that says so.
NoisyImage noisy(int w, int h, double sigma, std::uint64_t seed, double bias = 0.0, int bias_x0 = 0, int bias_x1 = 0,
                 int bias_y0 = 0, int bias_y1 = 0) {
  NoisyImage img{Image(w, h, 3), Image(w, h, 3)};
  Rng rng(seed, 7);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        const double u1 = std::max(rng.next_double(), 1e-300), u2 = rng.next_double();
        const double z = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
        double v = 0.2 + 0.5 * x / w + 0.1 * c + sigma * z;
        if (x >= bias_x0 && x < bias_x1 && y >= bias_y0 && y < bias_y1) v += bias;
        img.mean.at(x, y, c) = static_cast<float>(v);
        img.variance_of_mean.at(x, y, c) = static_cast<float>(sigma * sigma);
      }
  return img;
}

TEST(ImageComparison, BonferroniThresholdIsTheNormalQuantile) {
  // P(|Z| > 3.2905) = 1e-3 for one test; 768 tests at family rate 1e-3: 4.83.
  EXPECT_NEAR(bonferroni_threshold(1), 3.2905, 1e-3);
  EXPECT_NEAR(bonferroni_threshold(768), 4.83, 0.01);
}

TEST(ImageComparison, IndependentNoiseAgrees) {
  int disagreements = 0;
  for (std::uint64_t s = 0; s < 10; ++s) {
    const Comparison c = compare_images(noisy(64, 64, 0.05, 2 * s), noisy(64, 64, 0.05, 2 * s + 1));
    disagreements += c.agree ? 0 : 1;
    EXPECT_EQ(c.regions.size(), 16u * 16u * 3u);
    // Noise alone: the relMSE between the two is what their variances explain (within a few percent).
    EXPECT_NEAR(c.rel_mse_excess(), 0.0, 0.05 * c.rel_mse_between_noise);
  }
  EXPECT_EQ(disagreements, 0);  // the family false-alarm rate is 1e-3 per comparison
}

TEST(ImageComparison, PlantedBiasIsFoundWhereItWasPlanted) {
  // One region of the 16 x 16 grid (4 x 4 pixels of a 64 x 64 image) brighter by 0.15 in b: the standard
  // error of a region's mean difference is sqrt(16 * 2 * 0.05^2) / 16 = 0.0177, so z = -8.5, far beyond
  // the threshold 4.83, and no other region is biased.
  const NoisyImage a = noisy(64, 64, 0.05, 11);
  const NoisyImage b = noisy(64, 64, 0.05, 12, 0.15, 40, 44, 8, 12);
  const Comparison c = compare_images(a, b);
  EXPECT_FALSE(c.agree);
  ASSERT_FALSE(c.differing.empty());
  for (const RegionDifference& d : c.differing) {
    EXPECT_EQ(d.x0, 40);
    EXPECT_EQ(d.y0, 8);
    EXPECT_LT(d.z, 0.0);  // a - b, and b is the brighter
  }
  EXPECT_GT(c.rel_mse_excess(), 0.0);
}

TEST(ImageComparison, SmallBiasOverTheWholeImageIsFound) {
  // +0.005 everywhere: a region (16 x 16 pixels) has a standard error of sqrt(256 * 2 * 0.05^2) / 256 =
  // 0.0044, so no single region is significant (z ~ 1.1), but the image means (standard error of their
  // difference 0.05 sqrt(2) / 256 = 2.8e-4) see it at z ~ 18: what compare prints beside the verdict.
  const NoisyImage a = noisy(256, 256, 0.05, 21);
  const NoisyImage b = noisy(256, 256, 0.05, 22, 0.005, 0, 256, 0, 256);
  const ChannelMeans ma = channel_means(a), mb = channel_means(b);
  for (int c = 0; c < 3; ++c) {
    const double z = (mb.mean[c] - ma.mean[c]) / std::hypot(ma.standard_error[c], mb.standard_error[c]);
    EXPECT_GT(z, 10.0);
  }
  EXPECT_NEAR(ma.standard_error[0], 0.05 / 256.0, 1e-9);
}

TEST(ImageComparison, RelMseAgainstTruthMatchesTheNoise) {
  const NoisyImage a = noisy(128, 128, 0.02, 31);
  Image truth(128, 128, 3);
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x)
      for (int c = 0; c < 3; ++c) truth.at(x, y, c) = static_cast<float>(0.2 + 0.5 * x / 128.0 + 0.1 * c);
  const double measured = rel_mse(a.mean, truth), expected = expected_rel_mse(a, truth);
  EXPECT_NEAR(measured, expected, 0.05 * expected);
}

TEST(ImageComparison, RejectsMismatchedImages) {
  EXPECT_THROW(compare_images(noisy(8, 8, 0.1, 1), noisy(8, 9, 0.1, 2)), std::invalid_argument);
  NoisyImage grey = noisy(8, 8, 0.1, 1);
  grey.mean = Image(8, 8, 1);
  EXPECT_THROW(channel_means(grey), std::invalid_argument);
}

TEST(ImageComparison, NoiselessDifferenceIsFarBeyondTheThreshold) {
  NoisyImage a{Image(16, 16, 3), Image(16, 16, 3)}, b{Image(16, 16, 3), Image(16, 16, 3)};
  EXPECT_TRUE(compare_images(a, b).agree);  // both black and exact
  b.mean.at(3, 3, 1) = 0.5f;
  const Comparison c = compare_images(a, b);
  EXPECT_FALSE(c.agree);
  // Only the numerical floor (1e-5 of the region's level) stands against it.
  EXPECT_GT(c.max_abs_z, 1e4);
}

TEST(ImageComparison, RoundingDifferencesOfNoiselessRegionsAgree) {
  // A constant sky of 0.3 in both, one renderer a float ulp higher everywhere (what rounding a constant
  // differently gives): below the numerical floor (1e-5 relative). A 1e-3 relative difference is not.
  NoisyImage a{Image(32, 32, 3), Image(32, 32, 3)}, b{Image(32, 32, 3), Image(32, 32, 3)};
  for (float& v : a.mean.data) v = 0.3f;
  for (float& v : b.mean.data) v = std::nextafter(0.3f, 1.0f);
  EXPECT_TRUE(compare_images(a, b).agree);
  for (float& v : b.mean.data) v = 0.3f * 1.001f;
  EXPECT_FALSE(compare_images(a, b).agree);
}

}  // namespace
}  // namespace twinray::compare
