#pragma once
// The first four dimensions of the Sobol sequence and hash-based Owen scrambling, after Burley, "Practical
// Hash-based Owen Scrambling", JCGT 9(4), 2020.
//
// Why these pieces: every prefix of 2^k points of a (0,2)-sequence puts exactly one point in each of the
// 2^k elementary intervals of every shape (2^a x 2^b cells, a + b = k), so a pixel's samples stratify every
// 2D pair of random numbers the path tracer draws, at every power-of-two sample count and nearly as well in
// between. Owen scrambling (a random permutation of every binary digit, nested on the digits above it) keeps
// that property, makes each point uniformly distributed (so estimates stay unbiased) and removes the
// structure that makes unscrambled sequences alias. The hash is Burley's: a Laine-Karras style permutation
// applied to the bit-reversed value, which reverses the direction in which bits influence each other so
// that each bit depends on the bits *above* it, as nested scrambling requires. Dimensions 2 and 3 serve the
// 4D sampler (sampler.h): the four dimensions together stratify pairs of 2D values jointly, which the
// (0,2)-sequence of dimensions 0 and 1 alone cannot.

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

// Dimensions 1 to 3 with Joe and Kuo's direction numbers (file new-joe-kuo-6.21201 of S. Joe and F. Y. Kuo,
// "Constructing Sobol sequences with better two-dimensional projections", SIAM J. Sci. Comput. 30, 2008):
// the degree s of the primitive polynomial, its inner coefficients a (bit s - 1 - j is the coefficient of
// x^(s - j)) and the initial odd integers m_1..m_s. Dimensions 0 to 3 form a (3,4)-sequence (Sobol's bound:
// the sum of degree - 1); the pair (0, 1) is a (0,2)-sequence, the pair (2, 3) is less even: its first 2^m
// points are (t,m,2)-nets with t = 1 for m = 5 to 10 (t = 2 at m = 3, 11, 12).
struct SobolPolynomial {
  int degree;
  std::uint32_t inner_coefficients;
  std::uint32_t initial[3];
};
inline constexpr SobolPolynomial kSobolPolynomials[4] = {
    {0, 0, {}},         // dimension 0: van der Corput, direction numbers 2^-(k+1)
    {1, 0, {1}},        // x + 1: the rows of Pascal's triangle mod 2
    {2, 1, {1, 3}},     // x^2 + x + 1
    {3, 1, {1, 3, 1}},  // x^3 + x + 1
};
inline constexpr int kSobolDimensions = 4;

// The 32 direction numbers of dimension d as 0.32 fractions: v_k = m_{k+1} / 2^(k+1) for k < s, then
// v_k = v_{k-s} xor (v_{k-s} >> s) xor (xor over j = 1..s-1 of a_j v_{k-j}). Point i of the dimension is the
// xor of v_k over the set bits k of i (index order, not Gray-code order).
struct DirectionNumbers {
  std::uint32_t v[32];
};
constexpr DirectionNumbers direction_numbers(int d) {
  DirectionNumbers out{};
  const SobolPolynomial& p = kSobolPolynomials[d];
  for (int k = 0; k < 32; ++k) {
    if (d == 0) {
      out.v[k] = 0x80000000u >> k;
    } else if (k < p.degree) {
      out.v[k] = p.initial[k] << (31 - k);
    } else {
      std::uint32_t x = out.v[k - p.degree] ^ (out.v[k - p.degree] >> p.degree);
      for (int j = 1; j < p.degree; ++j)
        if ((p.inner_coefficients >> (p.degree - 1 - j)) & 1u) x ^= out.v[k - j];
      out.v[k] = x;
    }
  }
  return out;
}

// Point `index` of dimension d, one bit at a time: the definition the tables below are checked against.
constexpr std::uint32_t sobol_point(int d, std::uint32_t index) {
  const DirectionNumbers dn = direction_numbers(d);
  std::uint32_t x = 0;
  for (int k = 0; k < 32; ++k)
    if ((index >> k) & 1u) x ^= dn.v[k];
  return x;
}

// Shuffled indices (below) use all 32 bits, so a dimension's xor is taken a byte at a time from tables of
// the xors of every byte value at each of the four byte positions (4 KiB a dimension): four loads instead of
// up to 32 steps. Every dimension is linear over GF(2) (xors of direction numbers), and so is its composition
// with bit reversal on both sides, z -> reverse_bits(dimension_d(reverse_bits(z))): the sampler keeps its
// shuffled indices bit-reversed (see Sampler::next_2d) and reads that composition from tables built the same
// way, which saves two bit reversals per value. `reversed` selects which of the two maps a table holds.
struct DimensionTables {
  std::uint32_t byte[4][256];
};
constexpr DimensionTables make_dimension_tables(int d, bool reversed) {
  DimensionTables t{};
  const DirectionNumbers dn = direction_numbers(d);
  auto reverse = [](std::uint32_t x) {
    std::uint32_t r = 0;
    for (int bit = 0; bit < 32; ++bit) r |= ((x >> bit) & 1u) << (31 - bit);
    return r;
  };
  for (int b = 0; b < 4; ++b)
    for (int value = 0; value < 256; ++value) {
      std::uint32_t x = 0;
      for (int bit = 0; bit < 8; ++bit) {
        if (!(value & (1 << bit))) continue;
        // In the reversed map, bit j of z is bit 31 - j of the index, whose direction number is v[31 - j].
        const int j = 8 * b + bit;
        x ^= reversed ? reverse(dn.v[31 - j]) : dn.v[j];
      }
      t.byte[b][value] = x;
    }
  return t;
}
inline constexpr DimensionTables kDimension1 = make_dimension_tables(1, false);
inline constexpr DimensionTables kReversedDimensions[kSobolDimensions - 1] = {
    make_dimension_tables(1, true), make_dimension_tables(2, true), make_dimension_tables(3, true)};

inline std::uint32_t lookup(const DimensionTables& t, std::uint32_t x) {
  return t.byte[0][x & 0xFFu] ^ t.byte[1][(x >> 8) & 0xFFu] ^ t.byte[2][(x >> 16) & 0xFFu] ^ t.byte[3][x >> 24];
}

inline std::uint32_t dimension1(std::uint32_t index) { return lookup(kDimension1, index); }

// reverse_bits(dimension_d(reverse_bits(z))) for d in 1..3 (for d = 0 it is reverse_bits(z)).
template <int d>
inline std::uint32_t reversed_dimension_of_reversed(std::uint32_t z) {
  static_assert(d >= 1 && d < kSobolDimensions);
  return lookup(kReversedDimensions[d - 1], z);
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
