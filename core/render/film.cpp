#include "core/render/film.h"

#include <limits>

namespace twinray {

Film::Film(int width, int height, const AuxChannels& aux) : width_(width), height_(height), aux_(aux) {
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  pixels_.resize(n);
  if (aux.normals) normals_.assign(n, glm::dvec3(0.0));
  if (aux.albedo) albedo_.assign(n, glm::dvec3(0.0));
  if (aux.cost) cost_.assign(n, glm::dvec3(0.0));
  if (aux.depth) {
    depth_.assign(n, 0.0);
    depth_hits_.assign(n, 0);
  }
}

namespace {

Image rgb_image_from(int w, int h, const std::vector<glm::dvec3>& sums, const std::vector<Film::PixelSums>& px) {
  Image img(w, h, 3);
  for (std::size_t i = 0; i < px.size(); ++i) {
    const double n = static_cast<double>(px[i].samples);
    if (n == 0.0) continue;
    for (int c = 0; c < 3; ++c) img.data[3 * i + static_cast<std::size_t>(c)] = static_cast<float>(sums[i][c] / n);
  }
  return img;
}

}  // namespace

Image Film::mean_image() const {
  Image img(width_, height_, 3);
  for (std::size_t i = 0; i < pixels_.size(); ++i) {
    const double n = static_cast<double>(pixels_[i].samples);
    if (n == 0.0) continue;
    for (int c = 0; c < 3; ++c)
      img.data[3 * i + static_cast<std::size_t>(c)] = static_cast<float>(pixels_[i].sum[c] / n);
  }
  return img;
}

Image Film::variance_of_mean_image() const {
  Image img(width_, height_, 3);
  for (std::size_t i = 0; i < pixels_.size(); ++i) {
    const double n = static_cast<double>(pixels_[i].samples);
    if (n < 2.0) continue;
    for (int c = 0; c < 3; ++c) {
      const double mean = pixels_[i].sum[c] / n;
      const double var = std::max(0.0, (pixels_[i].sum_sq[c] - n * mean * mean) / (n - 1.0));
      img.data[3 * i + static_cast<std::size_t>(c)] = static_cast<float>(var / n);
    }
  }
  return img;
}

Image Film::normals_image() const { return aux_.normals ? rgb_image_from(width_, height_, normals_, pixels_) : Image(); }
Image Film::albedo_image() const { return aux_.albedo ? rgb_image_from(width_, height_, albedo_, pixels_) : Image(); }
Image Film::cost_image() const { return aux_.cost ? rgb_image_from(width_, height_, cost_, pixels_) : Image(); }

Image Film::depth_image() const {
  if (!aux_.depth) return Image();
  Image img(width_, height_, 1);
  for (std::size_t i = 0; i < pixels_.size(); ++i)
    img.data[i] = depth_hits_[i] > 0 ? static_cast<float>(depth_[i] / depth_hits_[i])
                                     : std::numeric_limits<float>::infinity();
  return img;
}

std::uint64_t Film::total_samples() const {
  std::uint64_t n = 0;
  for (const PixelSums& p : pixels_) n += p.samples;
  return n;
}

}  // namespace twinray
