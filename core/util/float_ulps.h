#pragma once
// How many floats lie between two floats: the distance of their bit patterns on the number line, so that
// "t is 3 ulps from the exact one" can be said about any two finite floats, across zero included (+0 and
// -0 are 0 apart).

#include <bit>
#include <cstdint>
#include <cstdlib>

namespace twinray {

// Bits of f mapped to an integer that increases with f (negative floats mirrored below zero).
inline std::int64_t ordered_float_bits(float f) {
  const std::int32_t i = std::bit_cast<std::int32_t>(f);
  return i >= 0 ? std::int64_t{i} : -std::int64_t{i & 0x7fffffff};
}

// |a - b| in units of the float spacing between them; both must be finite (NaN has no place on the line).
inline std::int64_t float_ulp_distance(float a, float b) {
  return std::llabs(ordered_float_bits(a) - ordered_float_bits(b));
}

}  // namespace twinray
