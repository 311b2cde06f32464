// The Owen-scrambled Sobol samplers (core/sampling/sobol.h, sampler.h), padded 2D and 4D: the direction
// numbers, stratification of every dimension (and of the 4D points) at power-of-two sample counts,
// determinism, unbiasedness of the scrambling, and images that do not depend on the thread count.

#include "render_test_util.h"

#include "core/sampling/sampler.h"
#include "core/sampling/sobol.h"
#include "core/scene/scene_loader.h"

#include <gtest/gtest.h>

#include <array>
#include <map>
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

TEST(Sobol, DirectionNumbersFollowJoeKuo) {
  // The first direction numbers from the recurrence over Joe and Kuo's (s, a, m): dimension 2 (x^2 + x + 1,
  // m = 1, 3) has v = 1/2, 3/4, then v_2 = v_0 ^ v_0 >> 2 ^ v_1 = 3/8, v_3 = v_1 ^ v_1 >> 2 ^ v_2 = 9/16;
  // dimension 3 (x^3 + x + 1, m = 1, 3, 1) has 1/2, 3/4, 1/8, then v_3 = v_0 ^ v_0 >> 3 ^ v_1 = 5/16.
  const std::uint32_t d2[4] = {0x80000000u, 0xC0000000u, 0x60000000u, 0x90000000u};
  const std::uint32_t d3[4] = {0x80000000u, 0xC0000000u, 0x20000000u, 0x50000000u};
  const sobol::DirectionNumbers v2 = sobol::direction_numbers(2), v3 = sobol::direction_numbers(3);
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(v2.v[k], d2[k]) << k;
    EXPECT_EQ(v3.v[k], d3[k]) << k;
  }
  // Dimension 1 from the generic recurrence is the Pascal-triangle dimension above.
  for (std::uint32_t i = 0; i < 8; ++i) EXPECT_EQ(sobol::sobol_point(1, i), sobol::dimension1(i)) << i;
}

TEST(Sobol, ByteTablesMatchTheBitwiseDefinition) {
  // The tables the sampler reads are the dimension seen through bit reversal, on full 32-bit indices.
  Rng rng(3, 4);
  for (int n = 0; n < 2000; ++n) {
    const std::uint32_t z = rng.next_u32();
    const std::uint32_t index = sobol::reverse_bits(z);
    EXPECT_EQ(sobol::dimension1(index), sobol::sobol_point(1, index));
    EXPECT_EQ(sobol::reversed_dimension_of_reversed<1>(z), sobol::reverse_bits(sobol::sobol_point(1, index)));
    EXPECT_EQ(sobol::reversed_dimension_of_reversed<2>(z), sobol::reverse_bits(sobol::sobol_point(2, index)));
    EXPECT_EQ(sobol::reversed_dimension_of_reversed<3>(z), sobol::reverse_bits(sobol::sobol_point(3, index)));
  }
}

// Whether the points form a (t, m, s)-net in base 2 (n = 2^m points in [0, 1)^s): every elementary interval
// of volume 2^(t - m) (2^k_j cells along axis j, sum k_j = m - t) holds exactly 2^t points.
template <std::size_t S>
bool is_net(const std::vector<std::array<float, S>>& pts, int t) {
  int m = 0;
  while ((std::size_t{1} << m) < pts.size()) ++m;
  std::array<int, S> k{};
  bool ok = true;
  // Every composition of m - t into S parts.
  auto visit = [&](auto&& self, std::size_t axis, int left) -> void {
    if (axis + 1 == S) {
      k[axis] = left;
      std::map<std::uint64_t, int> cells;
      for (const auto& p : pts) {
        std::uint64_t key = 0;
        for (std::size_t j = 0; j < S; ++j) key = (key << 16) | static_cast<std::uint64_t>(p[j] * static_cast<float>(1 << k[j]));
        ++cells[key];
      }
      ok = ok && cells.size() == (std::size_t{1} << (m - t));
      for (const auto& [key, count] : cells) ok = ok && count == (1 << t);
      return;
    }
    for (int a = 0; a <= left; ++a) {
      k[axis] = a;
      self(self, axis + 1, left - a);
    }
  };
  visit(visit, 0, m - t);
  return ok;
}

TEST(Sobol, FirstFourDimensionsFormA3Net) {
  // Sobol's bound: t = sum of (degree - 1) over the polynomials = 0 + 0 + 1 + 2 = 3. Not a 2-net: that is
  // what the 4D sampler trades for stratifying two 2D draws jointly.
  std::vector<std::array<float, 4>> pts;
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::array<float, 4> p{};
    for (int d = 0; d < 4; ++d) p[static_cast<std::size_t>(d)] = sobol::to_unit_float(sobol::sobol_point(d, i));
    pts.push_back(p);
  }
  EXPECT_TRUE(is_net(pts, 3));
  EXPECT_FALSE(is_net(pts, 2));
}

// The points of one pixel's first n samples in the sampler's 2D draw `dim` (0: the camera jitter).
std::vector<glm::vec2> pixel_points(std::uint64_t seed, std::uint64_t pixel, int n, int dim,
                                    SamplerKind kind = SamplerKind::Sobol) {
  std::vector<glm::vec2> out;
  for (int s = 0; s < n; ++s) {
    Sampler sampler(kind, seed, pixel, static_cast<std::uint32_t>(s));
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

TEST(Sobol4dSampler, FirstDrawOfEachPairStratifiesLikeAZeroTwoSequence) {
  // Draws 0, 2 and 8 take Sobol dimensions 0 and 1: one point in each of the 64 elementary intervals of
  // every shape. Draws 1 and 3 take dimensions 2 and 3, whose first 64 points are a (1, 6, 2)-net: two points
  // in each elementary interval of 32 cells.
  constexpr int kN = 64;
  for (std::uint64_t pixel : {0ull, 12345ull}) {
    for (int dim : {0, 2, 8}) {
      std::vector<std::array<float, 2>> pts;
      for (const glm::vec2& p : pixel_points(9, pixel, kN, dim, SamplerKind::Sobol4d)) pts.push_back({p.x, p.y});
      EXPECT_TRUE(is_net(pts, 0)) << "pixel " << pixel << " draw " << dim;
    }
    for (int dim : {1, 3}) {
      std::vector<std::array<float, 2>> pts;
      for (const glm::vec2& p : pixel_points(9, pixel, kN, dim, SamplerKind::Sobol4d)) pts.push_back({p.x, p.y});
      EXPECT_TRUE(is_net(pts, 1)) << "pixel " << pixel << " draw " << dim;
    }
  }
}

TEST(Sobol4dSampler, PairsOfDrawsStratifyJointly) {
  // 256 samples of a pixel: the 4D points (draw 2k, draw 2k + 1) are a scrambled block of 256 consecutive
  // Sobol points, hence a (3, 8, 4)-net like the unscrambled ones; a 1D draw between the two halves (the
  // roulette) changes nothing. With the padded sampler the same two draws are independent shuffles: not a
  // 3-net (the test's guard: is_net distinguishes them).
  constexpr int kN = 256;
  for (const bool roulette_between : {false, true})
    for (int pair : {0, 1, 4}) {
      std::vector<std::array<float, 4>> pts, padded;
      for (int s = 0; s < kN; ++s) {
        Sampler a(SamplerKind::Sobol4d, 3, 999, static_cast<std::uint32_t>(s));
        Sampler b(SamplerKind::Sobol, 3, 999, static_cast<std::uint32_t>(s));
        for (int d = 0; d < 2 * pair; ++d) {
          (void)a.next_2d();
          (void)b.next_2d();
        }
        const glm::vec2 a0 = a.next_2d(), b0 = b.next_2d();
        if (roulette_between) (void)a.next_1d();
        const glm::vec2 a1 = a.next_2d(), b1 = b.next_2d();
        pts.push_back({a0.x, a0.y, a1.x, a1.y});
        padded.push_back({b0.x, b0.y, b1.x, b1.y});
      }
      EXPECT_TRUE(is_net(pts, 3)) << "pair " << pair << (roulette_between ? ", roulette between" : "");
      EXPECT_FALSE(is_net(padded, 3)) << "pair " << pair;
    }
}

TEST(Sobol4dSampler, OneDimensionalDrawsLeaveThePairAlone) {
  // The second draw of a pair is the same value whether a 1D draw came between the two or not.
  for (std::uint32_t s = 0; s < 16; ++s) {
    Sampler a(SamplerKind::Sobol4d, 1, 2, s), b(SamplerKind::Sobol4d, 1, 2, s);
    EXPECT_EQ(a.next_2d(), b.next_2d());
    (void)b.next_1d();
    EXPECT_EQ(a.next_2d(), b.next_2d()) << s;
  }
}

TEST(SamplerSplit, ContinuationsOfAPixelStratifyAsOneSet) {
  // 16 samples of a pixel, each split into 4 continuations after its first two 2D draws: the 64
  // continuations' next 2D draws are samples s * 4 + j of the same dimensions, so one point in each
  // elementary interval of 64 cells (a (0, 6, 2)-net); with Sobol4d the draw after that completes the pair
  // (dimensions 2 and 3: a (1, 6, 2)-net). Without the split index (all 4 continuations of a sample the
  // same) there would be only 16 distinct points.
  constexpr int kSamples = 16, kSplits = 4;
  for (const SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Sobol4d})
    for (std::uint64_t pixel : {3ull, 4242ull}) {
      std::vector<std::array<float, 2>> first, second;
      for (int s = 0; s < kSamples; ++s) {
        Sampler parent(kind, 5, pixel, static_cast<std::uint32_t>(s));
        (void)parent.next_2d();
        (void)parent.next_2d();
        for (std::uint32_t j = 0; j < kSplits; ++j) {
          Sampler c = parent.split(j, kSplits);
          const glm::vec2 a = c.next_2d(), b = c.next_2d();
          first.push_back({a.x, a.y});
          second.push_back({b.x, b.y});
        }
      }
      EXPECT_TRUE(is_net(first, 0)) << to_string(kind) << " pixel " << pixel;
      EXPECT_TRUE(is_net(second, kind == SamplerKind::Sobol4d ? 1 : 0)) << to_string(kind) << " pixel " << pixel;
    }
}

TEST(SamplerSplit, OneContinuationIsTheSamplerItselfAndIndependentStreamsDiffer) {
  // (After a whole Sobol4d pair: a split always starts a new pair.)
  for (const SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Sobol4d}) {
    Sampler a(kind, 1, 2, 3);
    (void)a.next_2d();
    (void)a.next_2d();
    Sampler b = a.split(0, 1);
    for (int d = 0; d < 5; ++d) EXPECT_EQ(a.next_2d(), b.next_2d()) << to_string(kind) << " draw " << d;
  }
  // Independent: continuations draw from unrelated streams, none of them the parent's own.
  Sampler parent(SamplerKind::Independent, 1, 2, 3);
  (void)parent.next_2d();
  std::set<float> firsts;
  for (std::uint32_t j = 0; j < 8; ++j) firsts.insert(parent.split(j, 8).next_1d());
  firsts.insert(Sampler(parent).next_1d());
  EXPECT_EQ(firsts.size(), 9u);
  // split() leaves the parent unchanged: the same continuation twice.
  EXPECT_EQ(parent.split(2, 8).next_2d(), parent.split(2, 8).next_2d());
}

TEST(SobolSampler, OneDimensionalDrawsStratify) {
  constexpr int kN = 32;
  for (const SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Sobol4d}) {
    std::set<int> bins;
    for (int s = 0; s < kN; ++s) {
      Sampler sampler(kind, 4, 77, static_cast<std::uint32_t>(s));
      (void)sampler.next_2d();
      bins.insert(static_cast<int>(sampler.next_1d() * kN));
    }
    EXPECT_EQ(bins.size(), static_cast<std::size_t>(kN)) << to_string(kind);
  }
}

TEST(SobolSampler, DeterministicAndKeyedBySeedPixelAndSample) {
  for (const SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Sobol4d}) {
    Sampler a(kind, 1, 2, 3), b(kind, 1, 2, 3);
    for (int i = 0; i < 10; ++i) EXPECT_EQ(a.next_2d(), b.next_2d()) << to_string(kind);
    // Both halves of the first pair depend on every key.
    auto first_two = [kind](std::uint64_t seed, std::uint64_t pixel, std::uint32_t sample) {
      Sampler s(kind, seed, pixel, sample);
      const glm::vec2 u = s.next_2d();
      return std::array<glm::vec2, 2>{u, s.next_2d()};
    };
    const std::array<glm::vec2, 2> base = first_two(1, 2, 3);
    for (const std::array<glm::vec2, 2>& other : {first_two(2, 2, 3), first_two(1, 3, 3), first_two(1, 2, 4)}) {
      EXPECT_NE(other[0], base[0]) << to_string(kind);
      EXPECT_NE(other[1], base[1]) << to_string(kind);
    }
  }
}

// Chi-square of counts against equal expected counts.
double chi_square(const std::vector<int>& count, int total) {
  const double expected = static_cast<double>(total) / static_cast<double>(count.size());
  double chi2 = 0.0;
  for (int c : count) chi2 += (c - expected) * (c - expected) / expected;
  return chi2;
}

TEST(SobolSampler, ScrambledPointsAreUniformOverSeeds) {
  // Unbiasedness needs each scrambled point to be uniform: over many pixels (independent scrambles) each
  // coordinate of the first sample's first two 2D draws lands in each of 16 bins about equally often
  // (chi-square, 15 dof; 40 is p < 5e-4), and with Sobol4d the four coordinates of the pair are jointly
  // uniform too (one bit of each: 16 cells of [0, 1)^4, same bound).
  constexpr int kBins = 16, kPixels = 16000;
  for (const SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Sobol4d}) {
    std::vector<std::vector<int>> count(4, std::vector<int>(kBins, 0));
    std::vector<int> joint(16, 0);
    std::vector<double> mean(4, 0.0);
    for (int p = 0; p < kPixels; ++p) {
      Sampler s(kind, 5, static_cast<std::uint64_t>(p), 0);
      const glm::vec2 u0 = s.next_2d(), u1 = s.next_2d();
      const float u[4] = {u0.x, u0.y, u1.x, u1.y};
      int cell = 0;
      for (std::size_t c = 0; c < 4; ++c) {
        mean[c] += u[c];
        ++count[c][static_cast<std::size_t>(u[c] * kBins)];
        cell = 2 * cell + (u[c] >= 0.5f ? 1 : 0);
      }
      ++joint[static_cast<std::size_t>(cell)];
    }
    for (std::size_t c = 0; c < 4; ++c) {
      EXPECT_LT(chi_square(count[c], kPixels), 40.0) << to_string(kind) << " coordinate " << c;
      EXPECT_NEAR(mean[c] / kPixels, 0.5, 4.0 * std::sqrt(1.0 / 12.0 / kPixels)) << to_string(kind) << " coordinate " << c;
    }
    EXPECT_LT(chi_square(joint, kPixels), 40.0) << to_string(kind);
  }
}

TEST(SobolSampler, ImageDoesNotDependOnThreadsOrPasses) {
  Scene scene = load_scene(std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes/cornell-mirror-glass.json");
  scene.camera.width = scene.camera.height = 32;
  for (const SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Sobol4d}) {
    RenderOptions o;
    o.spp = 8;
    o.sampler = kind;
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
    EXPECT_EQ(one.mean.data, two.mean.data) << to_string(kind);
    o.sampler = SamplerKind::Independent;
    EXPECT_NE(render_scene(scene, o).mean.data, two.mean.data) << to_string(kind);
  }
}

TEST(SamplerKind, NamesRoundTrip) {
  for (const SamplerKind kind : {SamplerKind::Independent, SamplerKind::Sobol, SamplerKind::Sobol4d})
    EXPECT_EQ(parse_sampler_kind(to_string(kind)), kind);
  EXPECT_FALSE(parse_sampler_kind("sobol8d").has_value());
}

}  // namespace
}  // namespace twinray
