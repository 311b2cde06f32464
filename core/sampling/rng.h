#pragma once
// PCG32 (O'Neill 2014): small state, good statistics, and independent streams, so every pixel sample can
// own a stream seeded by (seed, pixel, sample) and images do not depend on thread scheduling.

#include <cstdint>

namespace twinray {

// SplitMix64 finaliser: turns structured keys (seed, pixel, sample) into well-mixed 64-bit values.
inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

class Rng {
 public:
  Rng() : Rng(0, 0) {}
  Rng(std::uint64_t seed, std::uint64_t stream) { reseed(seed, stream); }

  // A generator keyed by three integers, e.g. (seed, pixel index, sample index).
  static Rng keyed(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
    return Rng(mix64(a ^ mix64(b ^ mix64(c))), mix64(b) ^ c);
  }

  void reseed(std::uint64_t seed, std::uint64_t stream) {
    state_ = 0;
    inc_ = (stream << 1u) | 1u;
    next_u32();
    state_ += seed;
    next_u32();
  }

  std::uint32_t next_u32() {
    const std::uint64_t old = state_;
    state_ = old * 6364136223846793005ull + inc_;
    const auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
    const auto rot = static_cast<std::uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31u));
  }

  // Uniform in [0, 1): 24 random mantissa bits, so the result is never rounded up to 1.
  float next_float() { return static_cast<float>(next_u32() >> 8) * 0x1p-24f; }
  double next_double() {
    const std::uint64_t hi = next_u32(), lo = next_u32();
    return static_cast<double>(((hi << 32) | lo) >> 11) * 0x1p-53;
  }
  // Uniform integer in [0, n) without modulo bias (Lemire's method).
  std::uint32_t next_below(std::uint32_t n) {
    std::uint64_t m = static_cast<std::uint64_t>(next_u32()) * n;
    auto low = static_cast<std::uint32_t>(m);
    if (low < n) {
      const std::uint32_t threshold = (0u - n) % n;
      while (low < threshold) {
        m = static_cast<std::uint64_t>(next_u32()) * n;
        low = static_cast<std::uint32_t>(m);
      }
    }
    return static_cast<std::uint32_t>(m >> 32);
  }

 private:
  std::uint64_t state_ = 0;
  std::uint64_t inc_ = 1;
};

}  // namespace twinray
