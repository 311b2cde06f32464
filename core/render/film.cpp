#include "core/render/film.h"

#include <algorithm>
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

void Film::enable_splats() { splats_.assign(pixels_.size(), SplatSums{}); }

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
  const bool splats = has_splats() && splat_spp_ > 0;
  const double spp = static_cast<double>(splat_spp_);
  for (std::size_t i = 0; i < pixels_.size(); ++i) {
    const double n = static_cast<double>(pixels_[i].samples);
    for (int c = 0; c < 3; ++c) {
      double v = n > 0.0 ? pixels_[i].sum[c] / n : 0.0;
      if (splats) v += splats_[i].sum[c] / spp;
      img.data[3 * i + static_cast<std::size_t>(c)] = static_cast<float>(v);
    }
  }
  return img;
}

Image Film::variance_of_mean_image() const {
  Image img(width_, height_, 3);
  const bool splats = has_splats() && splat_spp_ > 0;
  const double spp = static_cast<double>(splat_spp_);
  const double paths = spp * static_cast<double>(pixels_.size());
  for (std::size_t i = 0; i < pixels_.size(); ++i) {
    const double n = static_cast<double>(pixels_[i].samples);
    for (int c = 0; c < 3; ++c) {
      double var = 0.0;
      if (n >= 2.0) {
        const double mean = pixels_[i].sum[c] / n;
        var = std::max(0.0, (pixels_[i].sum_sq[c] - n * mean * mean) / (n - 1.0)) / n;
      }
      if (splats) {
        const double sum = splats_[i].sum[c];
        var += std::max(0.0, splats_[i].sum_sq[c] - sum * sum / paths) / (spp * spp);
      }
      img.data[3 * i + static_cast<std::size_t>(c)] = static_cast<float>(var);
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
