#pragma once
// The first two dimensions of the Sobol sequence (a (0,2)-sequence in base 2) and hash-based Owen
// scrambling, after Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4), 2020.
//
// Why these pieces: every prefix of 2^k points of a (0,2)-sequence puts exactly one point in each of the
// 2^k elementary intervals of every shape (2^a x 2^b cells, a + b = k), so a pixel's samples stratify every
// 2D pair of random numbers the path tracer draws, at every power-of-two sample count and nearly as well in
// between. Owen scrambling (a random permutation of every binary digit, nested on the digits above it) keeps
// that property, makes each point uniformly distributed (so estimates stay unbiased) and removes the
// structure that makes unscrambled sequences alias. The hash is Burley's: a Laine-Karras style permutation
// applied to the bit-reversed value, which reverses the direction in which bits influence each other so
// that each bit depends on the bits *above* it, as nested scrambling requires.

#include <bit>
#include <cstdint>

namespace twinray::sobol {

// Bits in reverse order: the bytes by one byte swap, the bits inside each byte by three mask-and-shift steps.
inline std::uint32_t reverse_bits(std::uint32_t x) {
  x = __builtin_bswap32(x);  // std::byteswap is C++23
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  return ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
}

// Dimension 0: the van der Corput sequence, the index's bits mirrored behind the binary point (as a 0.32
// fixed-point fraction).
inline std::uint32_t dimension0(std::uint32_t index) { return reverse_bits(index); }

// Dimension 1: primitive polynomial x + 1; its direction numbers are the rows of Pascal's triangle mod 2,
// v_0 = 2^31 and v_k = v_{k-1} xor (v_{k-1} >> 1); point i is the xor of v_k over the set bits k of i.
// Shuffled indices (below) use all 32 bits, so the xor is taken a byte at a time from tables of the xors of
// every byte value at each of the four byte positions (4 KiB): four loads instead of up to 32 steps.
inline constexpr struct Dimension1Tables {
  std::uint32_t byte[4][256];
  constexpr Dimension1Tables() : byte() {
    std::uint32_t v[32] = {};
    v[0] = 0x80000000u;
    for (int k = 1; k < 32; ++k) v[k] = v[k - 1] ^ (v[k - 1] >> 1);
    for (int b = 0; b < 4; ++b)
      for (int value = 0; value < 256; ++value) {
        std::uint32_t x = 0;
        for (int bit = 0; bit < 8; ++bit)
          if (value & (1 << bit)) x ^= v[8 * b + bit];
        byte[b][value] = x;
      }
  }
} kDimension1{};

inline std::uint32_t dimension1(std::uint32_t index) {
  return kDimension1.byte[0][index & 0xFFu] ^ kDimension1.byte[1][(index >> 8) & 0xFFu] ^
         kDimension1.byte[2][(index >> 16) & 0xFFu] ^ kDimension1.byte[3][index >> 24];
}

// The same map seen through bit reversal: reverse_bits(dimension1(reverse_bits(z))). Both are linear over
// GF(2) (xors of direction numbers), so their composition is too, and it is tabulated by the bytes of z the
// same way. The sampler keeps its shuffled indices bit-reversed (see Sampler::next_2d): this table then
// saves two of the bit reversals a 2D draw would otherwise make.
inline constexpr struct ReversedDimension1Tables {
  std::uint32_t byte[4][256];
  constexpr ReversedDimension1Tables() : byte() {
    std::uint32_t v[32] = {};
    v[0] = 0x80000000u;
    for (int k = 1; k < 32; ++k) v[k] = v[k - 1] ^ (v[k - 1] >> 1);
    auto reverse = [](std::uint32_t x) {
      std::uint32_t r = 0;
      for (int bit = 0; bit < 32; ++bit) r |= ((x >> bit) & 1u) << (31 - bit);
      return r;
    };
    // Bit j of z is bit 31 - j of the index, whose direction number is v[31 - j].
    for (int b = 0; b < 4; ++b)
      for (int value = 0; value < 256; ++value) {
        std::uint32_t x = 0;
        for (int bit = 0; bit < 8; ++bit)
          if (value & (1 << bit)) x ^= reverse(v[31 - (8 * b + bit)]);
        byte[b][value] = x;
      }
  }
} kReversedDimension1{};

inline std::uint32_t reversed_dimension1_of_reversed(std::uint32_t z) {
  return kReversedDimension1.byte[0][z & 0xFFu] ^ kReversedDimension1.byte[1][(z >> 8) & 0xFFu] ^
         kReversedDimension1.byte[2][(z >> 16) & 0xFFu] ^ kReversedDimension1.byte[3][z >> 24];
}

// Burley's hash of a bit-reversed value (constants from the paper): each output bit depends only on the
// seed and on input bits below it.
inline std::uint32_t laine_karras_permutation(std::uint32_t x, std::uint32_t seed) {
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}

// Owen scrambling of a 0.32 fixed-point value: each bit is flipped by a hash of the seed and of the bits
// above it.
inline std::uint32_t nested_uniform_scramble(std::uint32_t x, std::uint32_t seed) {
  return reverse_bits(laine_karras_permutation(reverse_bits(x), seed));
}

// A 0.32 fixed-point fraction as a float in [0, 1): the top 24 bits, so it never rounds up to 1.
inline float to_unit_float(std::uint32_t x) { return static_cast<float>(x >> 8) * 0x1p-24f; }

}  // namespace twinray::sobol
