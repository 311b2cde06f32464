#pragma once
// Per-pixel accumulation of radiance samples (box filter: every sample counts for the pixel it was taken
// in, with equal weight) and of the auxiliary first-hit quantities.
//
// Sums are kept in double with their squares, so the mean and the sample variance of each pixel are
// available (tests derive their tolerances from the latter). Each pixel is written by one task at a time
// and its samples are added in sample-index order, so the sums do not depend on thread scheduling.
//
// Splats: a light tracer (core/render/light_tracer.h) adds contributions to arbitrary pixels. They are
// summed apart from the camera samples, with their squares, in the order of the light paths' global
// indices (the renderer merges them in that order), so they are as deterministic as the camera sums. A
// pixel's value is then camera_sum / camera_samples + splat_sum / splat_spp, where splat_spp is the number
// of light paths divided by the pixel count (one light path per camera sample: the samples per pixel).

#include "core/image/image.h"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace twinray {

struct AuxChannels {
  bool normals = false;
  bool albedo = false;
  bool depth = false;
  bool cost = false;  // traversal cost; only honoured for backends that count traversal
  bool any() const { return normals || albedo || depth || cost; }
};

class Film {
 public:
  Film(int width, int height, const AuxChannels& aux);

  int width() const { return width_; }
  int height() const { return height_; }
  const AuxChannels& aux() const { return aux_; }

  struct PixelSums {
    glm::dvec3 sum{0.0};
    glm::dvec3 sum_sq{0.0};
    std::uint64_t samples = 0;
  };
  PixelSums& pixel(std::size_t index) { return pixels_[index]; }
  const PixelSums& pixel(std::size_t index) const { return pixels_[index]; }

  // Auxiliary sums per pixel (only allocated for the channels asked for).
  glm::dvec3* normal_sum(std::size_t index) { return aux_.normals ? &normals_[index] : nullptr; }
  glm::dvec3* albedo_sum(std::size_t index) { return aux_.albedo ? &albedo_[index] : nullptr; }
  double* depth_sum(std::size_t index) { return aux_.depth ? &depth_[index] : nullptr; }
  // Number of samples whose camera ray hit something (the depth is averaged over those).
  std::uint32_t* depth_hit_count(std::size_t index) { return aux_.depth ? &depth_hits_[index] : nullptr; }
  glm::dvec3* cost_sum(std::size_t index) { return aux_.cost ? &cost_[index] : nullptr; }

  // Light-tracer splats (see above); allocated by enable_splats(), the normalisation set by
  // set_splat_samples_per_pixel() once the render knows how many light paths it traced.
  struct SplatSums {
    glm::dvec3 sum{0.0};
    glm::dvec3 sum_sq{0.0};
  };
  void enable_splats();
  bool has_splats() const { return !splats_.empty(); }
  void add_splat(std::size_t index, const glm::dvec3& value) {
    SplatSums& s = splats_[index];
    s.sum += value;
    s.sum_sq += value * value;
  }
  const SplatSums& splat(std::size_t index) const { return splats_[index]; }
  void set_splat_samples_per_pixel(std::uint64_t spp) { splat_spp_ = spp; }
  std::uint64_t splat_samples_per_pixel() const { return splat_spp_; }

  // The mean radiance per pixel (RGB), splats included.
  Image mean_image() const;
  // The variance of each pixel's mean (sample variance / n), RGB; 0 where n < 2. Splats add the variance
  // of their sum over N = splat_spp * W * H light paths, each light path's contribution to the pixel taken
  // as one draw (0 for most): (sum_sq - sum^2 / N) / splat_spp^2. A light path splatting twice into one
  // pixel counts as two draws, which slightly underestimates its share; that happens only for paths that
  // revisit the surface seen in the pixel.
  Image variance_of_mean_image() const;
  // Auxiliary images (empty when not asked for), means over all samples of the pixel, misses counting as
  // 0: normals (xyz), albedo (RGB), cost (nodes visited, primitives tested, rays, per camera sample); depth
  // is the mean over the samples that hit (1 channel, +inf where every sample missed).
  Image normals_image() const;
  Image albedo_image() const;
  Image depth_image() const;
  Image cost_image() const;

  std::uint64_t total_samples() const;

 private:
  int width_, height_;
  AuxChannels aux_;
  std::vector<PixelSums> pixels_;
  std::vector<SplatSums> splats_;
  std::uint64_t splat_spp_ = 0;
  std::vector<glm::dvec3> normals_, albedo_, cost_;
  std::vector<double> depth_;
  std::vector<std::uint32_t> depth_hits_;
};

}  // namespace twinray
