// The Owen-scrambled Sobol sampler (core/sampling/sobol.h, sampler.h): stratification of every dimension at
// power-of-two sample counts, determinism, unbiasedness of the scrambling, and images that do not depend on
// the thread count.

#include "render_test_util.h"

#include "core/sampling/sampler.h"
#include "core/sampling/sobol.h"
#include "core/scene/scene_loader.h"

#include <gtest/gtest.h>

#include <set>
#include <vector>

namespace twinray {
namespace {

using namespace twinray::test;

TEST(Sobol, FirstDimensionsAreTheKnownSequence) {
  // Sobol points 0..7 in dimensions 0 and 1 (as 0.32 fractions), point i being the xor of the direction
  // numbers of i's set bits (index order, not Gray-code order): v = 1/2, 1/4, 1/8 and 1/2, 3/4, 5/8.
  const double d0[8] = {0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875};
  const double d1[8] = {0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875};
  for (std::uint32_t i = 0; i < 8; ++i) {
    EXPECT_EQ(sobol::dimension0(i) * 0x1p-32, d0[i]) << i;
    EXPECT_EQ(sobol::dimension1(i) * 0x1p-32, d1[i]) << i;
  }
  EXPECT_EQ(sobol::reverse_bits(1u), 0x80000000u);
  EXPECT_EQ(sobol::reverse_bits(0x12345678u), 0x1E6A2C48u);
}

TEST(Sobol, ScramblingIsABijectionOnEachPrefix) {
  // Owen scrambling permutes the 2^k intervals of each level: the first 4 bits of 16 distinct 4-bit values
  // stay distinct after scrambling, for any seed.
  for (std::uint32_t seed : {0u, 1u, 0xdeadbeefu}) {
    std::set<std::uint32_t> top;
    for (std::uint32_t v = 0; v < 16; ++v) top.insert(sobol::nested_uniform_scramble(v << 28, seed) >> 28);
    EXPECT_EQ(top.size(), 16u) << seed;
  }
}

// The points of one pixel's first n samples in the sampler's dimension `dim` (0: the camera jitter).
std::vector<glm::vec2> pixel_points(std::uint64_t seed, std::uint64_t pixel, int n, int dim) {
  std::vector<glm::vec2> out;
  for (int s = 0; s < n; ++s) {
    Sampler sampler(SamplerKind::Sobol, seed, pixel, static_cast<std::uint32_t>(s));
    glm::vec2 p(0.0f);
    for (int d = 0; d <= dim; ++d) p = sampler.next_2d();
    out.push_back(p);
  }
  return out;
}

TEST(SobolSampler, EveryDimensionStratifiesAtPowersOfTwo) {
  // 64 samples: one point in each of the 64 elementary intervals of every shape 2^a x 2^b, a + b = 6, in
  // the first, third and eighth 2D dimension of two pixels.
  constexpr int kLog2 = 6, kN = 1 << kLog2;
  for (std::uint64_t pixel : {0ull, 12345ull})
    for (int dim : {0, 2, 7}) {
      const std::vector<glm::vec2> pts = pixel_points(9, pixel, kN, dim);
      for (int a = 0; a <= kLog2; ++a) {
        const int nx = 1 << a, ny = kN / nx;
        std::set<int> cells;
        for (const glm::vec2& p : pts)
          cells.insert(static_cast<int>(p.x * static_cast<float>(nx)) * ny + static_cast<int>(p.y * static_cast<float>(ny)));
        EXPECT_EQ(cells.size(), static_cast<std::size_t>(kN)) << "pixel " << pixel << " dim " << dim << " cells " << nx << "x" << ny;
      }
    }
}

TEST(SobolSampler, OneDimensionalDrawsStratify) {
  constexpr int kN = 32;
  std::set<int> bins;
  for (int s = 0; s < kN; ++s) {
    Sampler sampler(SamplerKind::Sobol, 4, 77, static_cast<std::uint32_t>(s));
    (void)sampler.next_2d();
    bins.insert(static_cast<int>(sampler.next_1d() * kN));
  }
  EXPECT_EQ(bins.size(), static_cast<std::size_t>(kN));
}

TEST(SobolSampler, DeterministicAndKeyedBySeedPixelAndSample) {
  Sampler a(SamplerKind::Sobol, 1, 2, 3), b(SamplerKind::Sobol, 1, 2, 3);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(a.next_2d(), b.next_2d());
  const glm::vec2 base = Sampler(SamplerKind::Sobol, 1, 2, 3).next_2d();
  EXPECT_NE(Sampler(SamplerKind::Sobol, 2, 2, 3).next_2d(), base);
  EXPECT_NE(Sampler(SamplerKind::Sobol, 1, 3, 3).next_2d(), base);
  EXPECT_NE(Sampler(SamplerKind::Sobol, 1, 2, 4).next_2d(), base);
}

TEST(SobolSampler, ScrambledPointsAreUniformOverSeeds) {
  // Unbiasedness needs each scrambled point to be uniform: over many pixels (independent scrambles) the
  // first sample's second coordinate lands in each of 16 bins about equally often (chi-square, 15 dof; 40 is p < 5e-4).
  constexpr int kBins = 16, kPixels = 16000;
  std::vector<int> count(kBins, 0);
  double mean = 0.0;
  for (int p = 0; p < kPixels; ++p) {
    Sampler s(SamplerKind::Sobol, 5, static_cast<std::uint64_t>(p), 0);
    const float x = s.next_2d().y;
    mean += x;
    ++count[static_cast<std::size_t>(x * kBins)];
  }
  double chi2 = 0.0;
  const double expected = static_cast<double>(kPixels) / kBins;
  for (int c : count) chi2 += (c - expected) * (c - expected) / expected;
  EXPECT_LT(chi2, 40.0);
  EXPECT_NEAR(mean / kPixels, 0.5, 4.0 * std::sqrt(1.0 / 12.0 / kPixels));
}

TEST(SobolSampler, ImageDoesNotDependOnThreadsOrPasses) {
  Scene scene = load_scene(std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes/cornell-mirror-glass.json");
  scene.camera.width = scene.camera.height = 32;
  RenderOptions o;
  o.spp = 8;
  o.sampler = SamplerKind::Sobol;
  Rendered two;
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = render_scene(scene, o);
  }
  Rendered one;
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = render_scene(scene, o);
  }
  EXPECT_EQ(one.mean.data, two.mean.data);
  o.sampler = SamplerKind::Independent;
  EXPECT_NE(render_scene(scene, o).mean.data, two.mean.data);
}

}  // namespace
}  // namespace twinray
