#pragma once
// A float image in memory: interleaved channels, row-major, top row first (the order EXR, PNG and
// latitude-longitude maps store rows in, so no flipping happens anywhere between file and memory).

#include <cstddef>
#include <stdexcept>
#include <vector>

namespace twinray {

struct Image {
  int width = 0, height = 0, channels = 3;
  std::vector<float> data;  // width * height * channels values, pixel (x, y) channel c at index(x, y, c)

  Image() = default;
  // Zero-filled. Throws std::invalid_argument for negative sizes or channels < 1.
  Image(int w, int h, int c = 3) : width(w), height(h), channels(c) {
    if (w < 0 || h < 0 || c < 1) throw std::invalid_argument("Image: negative size or no channels");
    data.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * static_cast<std::size_t>(c), 0.0f);
  }

  bool empty() const { return width <= 0 || height <= 0; }
  std::size_t pixel_count() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
  std::size_t index(int x, int y, int c = 0) const {
    return (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) *
               static_cast<std::size_t>(channels) +
           static_cast<std::size_t>(c);
  }
  float& at(int x, int y, int c = 0) { return data[index(x, y, c)]; }
  float at(int x, int y, int c = 0) const { return data[index(x, y, c)]; }
};

}  // namespace twinray
