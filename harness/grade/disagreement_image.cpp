#include "harness/grade/disagreement_image.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace twinray::grade {

namespace {
// Linear colours (write_png applies the sRGB curve).
constexpr float kBackground[3] = {0.02f, 0.03f, 0.08f};
constexpr float kWrong[3] = {1.0f, 0.0f, 0.0f};
}  // namespace

Image disagreement_image(int width, int height, std::span<const Ray> rays, std::span<const Hit> reference,
                         std::span<const WrongAnswer> wrong) {
  Image image(width, height, 3);
  const std::size_t pixels = image.pixel_count();
  const auto w = static_cast<std::size_t>(width);
  for (std::size_t p = 0; p < pixels && p < rays.size(); ++p) {
    const int x = static_cast<int>(p % w), y = static_cast<int>(p / w);
    const Hit& h = reference[p];
    if (!h.found()) {
      for (int c = 0; c < 3; ++c) image.at(x, y, c) = kBackground[c];
      continue;
    }
    const float len = glm::length(rays[p].dir);
    const float cosine = len > 0.0f ? std::fabs(glm::dot(h.ng, rays[p].dir)) / len : 0.0f;
    const float grey = 0.04f + 0.6f * (std::isfinite(cosine) ? std::min(cosine, 1.0f) : 0.0f);
    for (int c = 0; c < 3; ++c) image.at(x, y, c) = grey;
  }
  for (const WrongAnswer& wrong_answer : wrong) {
    if (wrong_answer.ray >= pixels) continue;
    const int x = static_cast<int>(wrong_answer.ray % w), y = static_cast<int>(wrong_answer.ray / w);
    for (int c = 0; c < 3; ++c) image.at(x, y, c) = kWrong[c];
  }
  const int factor = std::max(1, kMinImageSide / std::max({width, height, 1}));
  if (factor == 1) return image;
  Image large(width * factor, height * factor, 3);
  for (int y = 0; y < large.height; ++y)
    for (int x = 0; x < large.width; ++x)
      for (int c = 0; c < 3; ++c) large.at(x, y, c) = image.at(x / factor, y / factor, c);
  return large;
}

}  // namespace twinray::grade
