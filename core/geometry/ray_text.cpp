#include "core/geometry/ray_text.h"

#include <fmt/core.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace twinray {

namespace {

constexpr std::array<const char*, 8> kComponentNames = {"ox", "oy", "oz", "dx", "dy", "dz", "tmin", "tmax"};

bool is_separator(char c) { return c == ' ' || c == '\t' || c == ',' || c == '\n'; }

}  // namespace

Ray parse_ray(std::string_view text) {
  std::array<float, 8> v{};
  std::size_t count = 0, i = 0;
  while (true) {
    while (i < text.size() && is_separator(text[i])) ++i;
    if (i == text.size()) break;
    std::size_t end = i;
    while (end < text.size() && !is_separator(text[end])) ++end;
    const std::string token(text.substr(i, end - i));
    if (count == v.size())
      throw std::invalid_argument(fmt::format("a ray is 8 numbers 'ox oy oz dx dy dz tmin tmax'; found more, from '{}'", token));
    char* stop = nullptr;
    errno = 0;
    const float value = std::strtof(token.c_str(), &stop);
    // ERANGE on underflow still gives the correctly rounded (denormal or zero) value, which is what a replay
    // wants; only overflow of a finite literal is refused.
    const bool overflow = errno == ERANGE && std::isinf(value) && token.find("inf") == std::string::npos;
    if (stop != token.c_str() + token.size() || std::isnan(value) || overflow)
      throw std::invalid_argument(
          fmt::format("{} = '{}' is not a number (decimal or hexadecimal float, 'inf' allowed)", kComponentNames[count], token));
    v[count++] = value;
    i = end;
  }
  if (count != v.size())
    throw std::invalid_argument(fmt::format("a ray is 8 numbers 'ox oy oz dx dy dz tmin tmax', got {}", count));
  Ray r;
  r.org = {v[0], v[1], v[2]};
  r.dir = {v[3], v[4], v[5]};
  r.tmin = v[6];
  r.tmax = v[7];
  return r;
}

std::string hex_float(float value) {
  if (std::isnan(value)) return std::signbit(value) ? "-nan" : "nan";
  if (std::isinf(value)) return value < 0.0f ? "-inf" : "inf";
  // %a of the float promoted to double: exact, and normalised (a float denormal prints as 0x1.8p-140, not
  // in the float's own denormal form), so one value has one spelling.
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%a", static_cast<double>(value));
  return buffer;
}

std::string format_ray_hex(const Ray& r) {
  return fmt::format("{} {} {} {} {} {} {} {}", hex_float(r.org.x), hex_float(r.org.y), hex_float(r.org.z),
                     hex_float(r.dir.x), hex_float(r.dir.y), hex_float(r.dir.z), hex_float(r.tmin), hex_float(r.tmax));
}

std::string format_ray_decimal(const Ray& r) {
  return fmt::format("{:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g}", r.org.x, r.org.y, r.org.z, r.dir.x,
                     r.dir.y, r.dir.z, r.tmin, r.tmax);
}

}  // namespace twinray
