// Distribution1D / Distribution2D: probabilities are the normalised weights, sampling follows them
// (chi-square), zero weights are never sampled (including at CDF boundaries), densities integrate to 1.

#include "core/sampling/distribution_1d.h"
#include "core/sampling/distribution_2d.h"
#include "core/sampling/rng.h"

#include "tests/chi_square.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace twinray {
namespace {

using twinray::testing::chi_square_accepts;


const std::vector<float> kSparse = {0.0f, 1.0f, 0.0f, 0.0f, 5.0f, 2.0f, 0.0f, 3.0f, 0.5f, 0.0f};

TEST(Distribution1D, PmfIsNormalisedWeight) {
  const Distribution1D d(kSparse);
  ASSERT_EQ(d.size(), kSparse.size());
  EXPECT_DOUBLE_EQ(d.integral(), 11.5 / 10.0);
  double sum = 0.0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    EXPECT_FLOAT_EQ(d.pmf(i), kSparse[i] / 11.5f);
    sum += d.pmf(i);
  }
  EXPECT_NEAR(sum, 1.0, 1e-6);
}

TEST(Distribution1D, DiscreteSamplesFollowPmfAndSkipZeroWeights) {
  const Distribution1D d(kSparse);
  const int n = 200000;
  std::vector<double> observed(d.size(), 0.0), expected(d.size());
  Rng rng(1, 1);
  for (int i = 0; i < n; ++i) {
    float pmf = 0.0f, remapped = -1.0f;
    const std::size_t k = d.sample_discrete(rng.next_float(), &pmf, &remapped);
    ASSERT_LT(k, d.size());
    ASSERT_EQ(pmf, d.pmf(k));
    ASSERT_GE(remapped, 0.0f);
    ASSERT_LT(remapped, 1.0f);
    observed[k] += 1.0;
  }
  for (std::size_t k = 0; k < d.size(); ++k) expected[k] = n * static_cast<double>(kSparse[k]) / 11.5;
  EXPECT_TRUE(chi_square_accepts(observed, expected));
}

TEST(Distribution1D, ZeroWeightsNeverReturnedAtCdfBoundariesOrEnds) {
  const Distribution1D d(kSparse);
  // Every CDF value (as the float a caller would pass), its neighbours, and the extremes of [0,1) and
  // beyond: boundaries of flat runs are where a naive search returns the zero-weight bin.
  std::vector<float> us = {0.0f, -0.0f, 0x1.fffffep-1f, 1.0f, 2.0f, -1.0f, std::numeric_limits<float>::quiet_NaN()};
  double running = 0.0;
  for (float w : kSparse) {
    running += w;
    const auto c = static_cast<float>(running / 11.5);
    us.insert(us.end(), {c, std::nextafter(c, 0.0f), std::nextafter(c, 1.0f)});
  }
  for (float u : us) {
    float pmf = 0.0f;
    const std::size_t k = d.sample_discrete(u, &pmf);
    ASSERT_LT(k, d.size()) << "u = " << u;
    EXPECT_GT(kSparse[k], 0.0f) << "u = " << u << " gave zero-weight bin " << k;
    const float x = d.sample_continuous(u, &pmf);
    EXPECT_GT(pmf, 0.0f) << "u = " << u;
    EXPECT_GE(x, 0.0f);
    EXPECT_LT(x, 1.0f);
  }
}

TEST(Distribution1D, SparseMillionBinMapNeverSamplesEmptyBins) {
  // 1M bins, 90% empty, weights spanning 8 orders of magnitude: the size of a 1k x 1k environment map.
  const std::size_t n = 1u << 20;
  std::vector<float> w(n, 0.0f);
  Rng rng(9, 9);
  for (std::size_t i = 0; i < n; ++i)
    if (rng.next_below(10) == 0) w[i] = std::pow(10.0f, 8.0f * rng.next_float() - 4.0f);
  const Distribution1D d(w);
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) sum += d.pmf(i);
  EXPECT_NEAR(sum, 1.0, 1e-5);  // 1M float pmfs, each rounded by <= 6e-8 relative
  for (int i = 0; i < 100000; ++i) {
    const std::size_t k = d.sample_discrete(rng.next_float(), nullptr);
    ASSERT_GT(w[k], 0.0f) << "bin " << k;
  }
}

TEST(Distribution1D, ContinuousPdfIntegratesToOneAndMatchesSamples) {
  const Distribution1D d(kSparse);
  double integral = 0.0;
  const int steps = 10000;  // a multiple of the bin count: midpoints never straddle a bin edge
  for (int i = 0; i < steps; ++i) integral += d.pdf_continuous((static_cast<float>(i) + 0.5f) / steps) / steps;
  EXPECT_NEAR(integral, 1.0, 1e-6);

  Rng rng(2, 3);
  const int n = 200000, bins = 40;  // 4 histogram bins per weight bin: checks uniformity inside bins too
  std::vector<double> observed(bins, 0.0), expected(bins);
  for (int i = 0; i < n; ++i) {
    float pdf = 0.0f;
    std::size_t offset = 0;
    const float x = d.sample_continuous(rng.next_float(), &pdf, &offset);
    ASSERT_GE(x, 0.0f);
    ASSERT_LT(x, 1.0f);
    ASSERT_EQ(d.bin_of(x), offset);
    ASSERT_EQ(pdf, d.pdf_continuous(x));
    ASSERT_GT(pdf, 0.0f);
    observed[static_cast<std::size_t>(std::min(static_cast<int>(x * bins), bins - 1))] += 1.0;
  }
  for (int b = 0; b < bins; ++b) expected[static_cast<std::size_t>(b)] = n * static_cast<double>(kSparse[static_cast<std::size_t>(b / 4)]) / 11.5 / 4.0;
  EXPECT_TRUE(chi_square_accepts(observed, expected));
}

TEST(Distribution1D, AllZeroFallsBackToUniform) {
  const std::vector<float> zeros(4, 0.0f);
  const Distribution1D d(zeros);
  EXPECT_EQ(d.integral(), 0.0);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_FLOAT_EQ(d.pmf(i), 0.25f);
  float pmf = 0.0f;
  EXPECT_EQ(d.sample_discrete(0.6f, &pmf), 2u);
  EXPECT_FLOAT_EQ(pmf, 0.25f);
  EXPECT_EQ(d.pdf_continuous(0.3f), 1.0f);
}

TEST(Distribution1D, RejectsInvalidWeights) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  EXPECT_THROW(Distribution1D(std::vector<float>{}), std::invalid_argument);
  EXPECT_THROW(Distribution1D(std::vector<float>{1.0f, -1.0f}), std::invalid_argument);
  EXPECT_THROW(Distribution1D(std::vector<float>{1.0f, nan}), std::invalid_argument);
  EXPECT_THROW(Distribution1D(std::vector<float>{inf}), std::invalid_argument);
}

// 4 columns x 3 rows with an empty row and empty cells.
const std::vector<float> kGrid = {1.0f, 0.0f, 2.0f, 1.0f,   //
                                  0.0f, 0.0f, 0.0f, 0.0f,   //
                                  4.0f, 0.5f, 0.0f, 3.5f};  // sum 12

TEST(Distribution2D, PmfSumsToOneAndCellsFollowIt) {
  const Distribution2D d(kGrid, 4, 3);
  double sum = 0.0;
  for (int v = 0; v < 3; ++v)
    for (int u = 0; u < 4; ++u) {
      EXPECT_FLOAT_EQ(d.pmf(u, v), kGrid[static_cast<std::size_t>(v * 4 + u)] / 12.0f);
      sum += d.pmf(u, v);
    }
  EXPECT_NEAR(sum, 1.0, 1e-6);

  const int n = 200000;
  std::vector<double> observed(12, 0.0), expected(12);
  Rng rng(4, 4);
  for (int i = 0; i < n; ++i) {
    float pmf = 0.0f;
    glm::vec2 r(-1.0f);
    const glm::ivec2 c = d.sample_cell(glm::vec2(rng.next_float(), rng.next_float()), &pmf, &r);
    ASSERT_EQ(pmf, d.pmf(c.x, c.y));
    ASSERT_GE(r.x, 0.0f);
    ASSERT_LT(r.x, 1.0f);
    ASSERT_GE(r.y, 0.0f);
    ASSERT_LT(r.y, 1.0f);
    observed[static_cast<std::size_t>(c.y * 4 + c.x)] += 1.0;
  }
  for (std::size_t k = 0; k < 12; ++k) expected[k] = n * static_cast<double>(kGrid[k]) / 12.0;
  EXPECT_TRUE(chi_square_accepts(observed, expected));
}

TEST(Distribution2D, ContinuousPdfIntegratesToOneAndMatchesSamples) {
  const Distribution2D d(kGrid, 4, 3);
  EXPECT_DOUBLE_EQ(d.integral(), 1.0);  // sum 12 over 12 cells of area 1/12
  double integral = 0.0;
  const int su = 40, sv = 30;  // multiples of the grid: quadrature midpoints never on a cell edge
  for (int j = 0; j < sv; ++j)
    for (int i = 0; i < su; ++i)
      integral += d.pdf(glm::vec2((static_cast<float>(i) + 0.5f) / su, (static_cast<float>(j) + 0.5f) / sv)) / (su * sv);
  EXPECT_NEAR(integral, 1.0, 1e-6);

  const int n = 200000;
  std::vector<double> observed(12, 0.0), expected(12);
  Rng rng(5, 5);
  for (int i = 0; i < n; ++i) {
    float pdf = 0.0f;
    const glm::vec2 p = d.sample(glm::vec2(rng.next_float(), rng.next_float()), &pdf);
    ASSERT_GE(p.x, 0.0f);
    ASSERT_LT(p.x, 1.0f);
    ASSERT_GE(p.y, 0.0f);
    ASSERT_LT(p.y, 1.0f);
    ASSERT_EQ(pdf, d.pdf(p));  // the same function for sample and pdf: bit-equal
    ASSERT_GT(pdf, 0.0f);
    observed[static_cast<std::size_t>(static_cast<int>(p.y * 3) * 4 + static_cast<int>(p.x * 4))] += 1.0;
  }
  for (std::size_t k = 0; k < 12; ++k) expected[k] = n * static_cast<double>(kGrid[k]) / 12.0;
  EXPECT_TRUE(chi_square_accepts(observed, expected));
}

TEST(Distribution2D, RejectsBadShapes) {
  EXPECT_THROW(Distribution2D(kGrid, 5, 3), std::invalid_argument);
  EXPECT_THROW(Distribution2D(kGrid, 0, 3), std::invalid_argument);
  EXPECT_THROW(Distribution2D(std::vector<float>{1.0f, -2.0f}, 2, 1), std::invalid_argument);
}

}  // namespace
}  // namespace twinray
