#include "harness/converge/error_metrics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace twinray::converge {

namespace {

int compared_channels(const Image& image, const Image& reference) {
  if (image.width != reference.width || image.height != reference.height)
    throw std::invalid_argument("image and reference differ in size");
  if (image.channels != reference.channels) throw std::invalid_argument("image and reference differ in channel count");
  return std::min(image.channels, 3);
}

}  // namespace

ErrorMetrics compute_error(const Image& image, const Image& reference) {
  const int channels = compared_channels(image, reference);
  double rel = 0.0, sq = 0.0, abs_sum = 0.0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < channels; ++c) {
        const double r = reference.at(x, y, c);
        const double d = static_cast<double>(image.at(x, y, c)) - r;
        rel += d * d / (r * r + kRelMseEpsilon);
        sq += d * d;
        abs_sum += std::abs(d);
      }
  const double n = static_cast<double>(image.pixel_count()) * channels;
  if (n == 0.0) return {};
  return {rel / n, std::sqrt(sq / n), abs_sum / n};
}

Image relative_squared_error_image(const Image& image, const Image& reference) {
  const int channels = compared_channels(image, reference);
  Image out(image.width, image.height, 1);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      double rel = 0.0;
      for (int c = 0; c < channels; ++c) {
        const double r = reference.at(x, y, c);
        const double d = static_cast<double>(image.at(x, y, c)) - r;
        rel += d * d / (r * r + kRelMseEpsilon);
      }
      out.at(x, y) = static_cast<float>(rel / channels);
    }
  return out;
}

Image absolute_difference_image(const Image& image, const Image& reference) {
  const int channels = compared_channels(image, reference);
  Image out(image.width, image.height, 3);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const int k = std::min(c, channels - 1);
        out.at(x, y, c) = std::abs(image.at(x, y, k) - reference.at(x, y, k));
      }
  return out;
}

}  // namespace twinray::converge
