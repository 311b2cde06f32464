#pragma once
// The random numbers of one camera sample: which generator draws them, and in which order.
//
// The integrators ask for a sequence of 1D and 2D values ("dimensions"): the pixel jitter first, then per
// path vertex the light choice, the point on the light, the BSDF lobe, the BSDF direction and the Russian
// roulette. Two samplers answer:
//  - Independent: every value from PCG32 keyed by (seed, pixel, sample) (core/sampling/rng.h).
//  - Sobol (default): every dimension is its own Owen-scrambled (0,2)-sequence over the pixel's sample
//    index ("padded" Sobol, as in pbrt-v4's PaddedSobolSampler): a 2D draw takes Sobol dimensions 0 and 1,
//    a 1D draw dimension 0, each with its own scramble seed and its own shuffle of the sample index
//    (Burley 2020: the index is Owen-scrambled too, so that dimensions do not correlate). The seeds are a
//    hash of (seed, pixel, dimension), so the pixel's samples stratify every pair of values the path
//    tracer draws, and the image still depends only on (seed, pixel, sample): not on the thread count, the
//    tile order, or on --spp versus --time.
// Both give unbiased estimates with the same expectation. With Sobol the samples of a pixel are no longer
// independent, so the per-pixel sample variance (Film::variance_of_mean_image) overestimates the variance
// of the pixel's mean: statistical tolerances built on it become conservative, never too tight; independent
// batches with different seeds measure the variance exactly (twinray compare does that).

#include "core/sampling/rng.h"
#include "core/sampling/sobol.h"

#include <glm/vec2.hpp>

#include <cstdint>
#include <optional>
#include <string_view>

namespace twinray {

enum class SamplerKind { Independent, Sobol };

std::string_view to_string(SamplerKind k);
std::optional<SamplerKind> parse_sampler_kind(std::string_view name);

class Sampler {
 public:
  Sampler(SamplerKind kind, std::uint64_t seed, std::uint64_t pixel, std::uint32_t sample)
      : kind_(kind), reversed_sample_(sobol::reverse_bits(sample)) {
    if (kind == SamplerKind::Independent) rng_ = Rng::keyed(seed, pixel, sample);
    else pixel_key_ = mix64(seed ^ mix64(pixel + 0x51ed270b27a1e5d3ull));
  }

  SamplerKind kind() const { return kind_; }

  // The next dimension: one value in [0, 1).
  float next_1d() {
    if (kind_ == SamplerKind::Independent) return rng_.next_float();
    const std::uint64_t h = dimension_hash();
    const std::uint32_t index = sobol::reverse_bits(shuffle_reversed(h));
    return sobol::to_unit_float(sobol::reverse_bits(sobol::laine_karras_permutation(index, static_cast<std::uint32_t>(h >> 32))));
  }

  // The next dimension: a point in [0, 1)^2.
  //
  // In the words of sobol.h, with index = nested_uniform_scramble(sample, seed0):
  //   x = nested_uniform_scramble(dimension0(index), seed1), y = nested_uniform_scramble(dimension1(index), seed2).
  // Written out, nested_uniform_scramble(v) = reverse(LK(reverse(v))) and dimension0 = reverse, so pairs of
  // reversals cancel: with z = LK(reverse(sample), seed0) (the index, bit-reversed),
  //   index = reverse(z), x = reverse(LK(index, seed1)), y = reverse(LK(reverse(dimension1(reverse(z))), seed2)),
  // the last inner term read from a table (sobol::reversed_dimension1_of_reversed). Three bit reversals
  // instead of seven, and reverse(sample) is computed once per camera sample; the values are the same bits.
  glm::vec2 next_2d() {
    if (kind_ == SamplerKind::Independent) {
      const float x = rng_.next_float();
      const float y = rng_.next_float();
      return {x, y};
    }
    const std::uint64_t h = dimension_hash();
    const std::uint64_t h2 = mix64(h);
    const std::uint32_t z = shuffle_reversed(h);
    const std::uint32_t index = sobol::reverse_bits(z);
    const std::uint32_t x = sobol::reverse_bits(sobol::laine_karras_permutation(index, static_cast<std::uint32_t>(h >> 32)));
    const std::uint32_t y = sobol::reverse_bits(
        sobol::laine_karras_permutation(sobol::reversed_dimension1_of_reversed(z), static_cast<std::uint32_t>(h2)));
    return {sobol::to_unit_float(x), sobol::to_unit_float(y)};
  }

  // The same as next_1d(); the name Russian roulette and other generic code call.
  float next_float() { return next_1d(); }

 private:
  std::uint64_t dimension_hash() { return mix64(pixel_key_ + 0x9E3779B97F4A7C15ull * ++dimension_); }
  // The dimension's shuffled sample index, bit-reversed: LK(reverse(sample), seed) (see next_2d).
  std::uint32_t shuffle_reversed(std::uint64_t h) const {
    return sobol::laine_karras_permutation(reversed_sample_, static_cast<std::uint32_t>(h));
  }

  SamplerKind kind_;
  std::uint32_t reversed_sample_ = 0;  // Sobol only
  std::uint32_t dimension_ = 0;
  std::uint64_t pixel_key_ = 0;
  Rng rng_;
};

}  // namespace twinray
