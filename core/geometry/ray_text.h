#pragma once
// A ray as text, for command lines and messages that replay one ray bit for bit (`twinray trace --ray`, the
// reproduce lines of `twinray grade`, a plugin failure's message):
//
//   "ox oy oz dx dy dz tmin tmax"
//
// Eight numbers separated by spaces (or commas), each a decimal or a C99 hexadecimal float ("0x1.8p+0"),
// "inf" allowed; decimals round to the nearest float. format_ray_hex writes every component as an exact
// hexadecimal float (signed zeros kept), so parse_ray(format_ray_hex(r)) == r in every bit.

#include "core/geometry/ray.h"

#include <string>
#include <string_view>

namespace twinray {

// Throws std::invalid_argument saying which component is wrong.
Ray parse_ray(std::string_view text);

std::string format_ray_hex(const Ray& ray);
// The same components as decimals with 9 significant digits (enough to round-trip a float).
std::string format_ray_decimal(const Ray& ray);

// One float as an exact hexadecimal literal, e.g. "0x1.8p+0", "-0x0p+0", "inf".
std::string hex_float(float value);

}  // namespace twinray
