#pragma once
// The random numbers of one camera sample: which generator draws them, and in which order.
//
// The integrators ask for a sequence of 1D and 2D values ("dimensions"): the pixel jitter first, then per
// path vertex the light choice, the point on the light, the BSDF lobe, the BSDF direction and the Russian
// roulette. Three samplers answer:
//  - Independent: every value from PCG32 keyed by (seed, pixel, sample) (core/sampling/rng.h).
//  - Sobol: every dimension is its own Owen-scrambled (0,2)-sequence over the pixel's sample index
//    ("padded" Sobol, as in pbrt-v4's PaddedSobolSampler): a 2D draw takes Sobol dimensions 0 and 1,
//    a 1D draw dimension 0, each with its own scramble seed and its own shuffle of the sample index
//    (Burley 2020: the index is Owen-scrambled too, so that dimensions do not correlate).
//  - Sobol4d (default): the 2D draws go in consecutive pairs, each pair one Owen-scrambled point of Sobol
//    dimensions 0 to 3 with one shuffle of the index (Burley 2020's 4D padding): the first draw of a pair
//    is made as the Sobol sampler makes its 2D draws, the second takes dimensions 2 and 3 of the same point. The
//    integrators draw the pixel jitter, then per vertex the light sample and the BSDF sample, so the pairs
//    are (pixel jitter, first vertex's light sample) and then (vertex k's BSDF sample, vertex k + 1's light
//    sample): each direction a path takes is stratified jointly with the light sample where it lands, which
//    is the four-dimensional integrand of one bounce of indirect light. 1D draws (the roulette) are padded
//    as with Sobol and do not break the pairing. Measured on the Cornell box (docs/rendering.md#sampler):
//    the one-bounce noise drops by 5%, the whole image's by 2 to 3%, at no cost in time.
// The Sobol seeds are a hash of (seed, pixel, dimension), so the pixel's samples stratify every pair of
// values the path tracer draws, and the image still depends only on (seed, pixel, sample): not on the
// thread count, the tile order, or on --spp versus --time.
// All three give unbiased estimates with the same expectation (every scrambled point is uniformly
// distributed). With Sobol or Sobol4d the samples of a pixel are no longer
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

enum class SamplerKind { Independent, Sobol, Sobol4d };

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
  // the last inner term read from a table (sobol::reversed_dimension_of_reversed<1>). Three bit reversals
  // instead of seven, and reverse(sample) is computed once per camera sample; the values are the same bits.
  // Forced inline: called per vertex in the path integrator's loop, where GCC kept it out of line (0.7% of the
  // render's instructions, docs/rendering.md).
  [[gnu::always_inline]] glm::vec2 next_2d() {
    if (kind_ == SamplerKind::Independent) {
      const float x = rng_.next_float();
      const float y = rng_.next_float();
      return {x, y};
    }
    if (kind_ == SamplerKind::Sobol4d && second_of_pair_) {
      // Dimensions 2 and 3 of the point whose dimensions 0 and 1 the previous 2D draw returned: the same
      // shuffled index, two more scramble seeds.
      second_of_pair_ = false;
      const std::uint64_t h3 = mix64(pair_hash_);
      const std::uint32_t x = sobol::reverse_bits(sobol::laine_karras_permutation(
          sobol::reversed_dimension_of_reversed<2>(pair_z_), static_cast<std::uint32_t>(pair_hash_ >> 32)));
      const std::uint32_t y = sobol::reverse_bits(sobol::laine_karras_permutation(
          sobol::reversed_dimension_of_reversed<3>(pair_z_), static_cast<std::uint32_t>(h3)));
      return {sobol::to_unit_float(x), sobol::to_unit_float(y)};
    }
    const std::uint64_t h = dimension_hash();
    const std::uint64_t h2 = mix64(h);
    const std::uint32_t z = shuffle_reversed(h);
    const std::uint32_t index = sobol::reverse_bits(z);
    const std::uint32_t x = sobol::reverse_bits(sobol::laine_karras_permutation(index, static_cast<std::uint32_t>(h >> 32)));
    const std::uint32_t y = sobol::reverse_bits(
        sobol::laine_karras_permutation(sobol::reversed_dimension_of_reversed<1>(z), static_cast<std::uint32_t>(h2)));
    if (kind_ == SamplerKind::Sobol4d) {
      second_of_pair_ = true;
      pair_z_ = z;
      pair_hash_ = h2;  // its low half seeded dimension 1; the high half and mix64 of it seed dimensions 2, 3
    }
    return {sobol::to_unit_float(x), sobol::to_unit_float(y)};
  }

  // The same as next_1d(); the name Russian roulette and other generic code call.
  float next_float() { return next_1d(); }

  // A sampler for continuation j of k of this camera sample (path splitting, core/render/path_integrator.h),
  // drawing from this one's next dimension on. Sobol and Sobol4d take the same dimensions at sample index
  // s * k + j (s: this sampler's sample index), so a pixel's spp * k continuations are one stratified set of
  // spp * k samples of those dimensions (spp * k must stay below 2^32). A Sobol4d pair left half drawn is not
  // completed: the continuation starts a new pair. Independent: a PCG32 stream keyed by this stream's next
  // 64-bit value and j (unrelated to every camera sample's own stream). With k = 1 and j = 0 the Sobol
  // samplers return a copy of this one.
  Sampler split(std::uint32_t j, std::uint32_t k) const {
    Sampler s = *this;
    if (kind_ == SamplerKind::Independent) {
      Rng copy = rng_;
      const std::uint64_t hi = copy.next_u32();
      const std::uint64_t key = (hi << 32) | copy.next_u32();
      s.rng_ = Rng::keyed(key, j, kSplitStreamKey);
      return s;
    }
    s.reversed_sample_ = sobol::reverse_bits(sobol::reverse_bits(reversed_sample_) * k + j);
    s.second_of_pair_ = false;
    return s;
  }

 private:
  std::uint64_t dimension_hash() { return mix64(pixel_key_ + 0x9E3779B97F4A7C15ull * ++dimension_); }
  // The dimension's shuffled sample index, bit-reversed: LK(reverse(sample), seed) (see next_2d).
  std::uint32_t shuffle_reversed(std::uint64_t h) const {
    return sobol::laine_karras_permutation(reversed_sample_, static_cast<std::uint32_t>(h));
  }

  static constexpr std::uint64_t kSplitStreamKey = 0x73706c6974ull;  // "split"

  SamplerKind kind_;
  bool second_of_pair_ = false;        // Sobol4d: the next 2D draw completes the current 4D point
  std::uint32_t pair_z_ = 0;           // Sobol4d: that point's shuffled index, bit-reversed
  std::uint64_t pair_hash_ = 0;        // Sobol4d: the hash its dimensions 2 and 3 take their seeds from
  std::uint32_t reversed_sample_ = 0;  // Sobol and Sobol4d
  std::uint32_t dimension_ = 0;
  std::uint64_t pixel_key_ = 0;
  Rng rng_;
};

}  // namespace twinray
