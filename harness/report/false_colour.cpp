#include "harness/report/false_colour.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace twinray::report {

namespace {

// Control points of the ramp in sRGB display values, evenly spaced in t; lightness rises monotonically.
constexpr std::array<glm::vec3, 6> kRamp = {{
    {0.05f, 0.03f, 0.20f},  // near-black blue
    {0.25f, 0.10f, 0.55f},  // violet
    {0.62f, 0.18f, 0.55f},  // magenta
    {0.90f, 0.38f, 0.30f},  // coral
    {0.98f, 0.68f, 0.20f},  // orange
    {0.99f, 0.96f, 0.65f},  // pale yellow
}};

float srgb_to_linear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

glm::vec3 colour_ramp_srgb(float t) {
  if (!(t > 0.0f)) return kRamp.front();
  if (t >= 1.0f) return kRamp.back();
  const float x = t * static_cast<float>(kRamp.size() - 1);
  const auto i = static_cast<std::size_t>(x);
  const float f = x - static_cast<float>(i);
  return kRamp[i] + f * (kRamp[i + 1] - kRamp[i]);
}

Image false_colour(const Image& scalar, const ScalarRange& range) {
  Image out(scalar.width, scalar.height, 3);
  const bool log = range.log && range.lo > 0.0 && range.hi > 0.0;
  const double lo = log ? std::log10(range.lo) : range.lo;
  const double hi = log ? std::log10(range.hi) : range.hi;
  const double span = hi > lo ? hi - lo : 1.0;
  for (int y = 0; y < scalar.height; ++y)
    for (int x = 0; x < scalar.width; ++x) {
      double v = scalar.at(x, y, 0);
      if (log) v = v > 0.0 ? std::log10(v) : lo;
      const glm::vec3 c = colour_ramp_srgb(static_cast<float>((v - lo) / span));
      for (int k = 0; k < 3; ++k) out.at(x, y, k) = srgb_to_linear(c[k]);
    }
  return out;
}

ScalarRange percentile_range(const Image& scalar, double p, double q, bool log) {
  std::vector<float> values;
  values.reserve(scalar.pixel_count());
  for (int y = 0; y < scalar.height; ++y)
    for (int x = 0; x < scalar.width; ++x) {
      const float v = scalar.at(x, y, 0);
      if (std::isfinite(v) && v > 0.0f) values.push_back(v);
    }
  if (values.empty()) return {0.0, 1.0, false};
  std::sort(values.begin(), values.end());
  auto at = [&](double f) {
    const auto k = static_cast<std::size_t>(std::clamp(f, 0.0, 1.0) * static_cast<double>(values.size() - 1));
    return static_cast<double>(values[k]);
  };
  ScalarRange r{at(p), at(q), log};
  if (!(r.hi > r.lo)) r.hi = r.lo * 2.0 + 1e-12;
  return r;
}

}  // namespace twinray::report
