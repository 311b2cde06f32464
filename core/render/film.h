#pragma once
// Per-pixel accumulation of radiance samples (box filter: every sample counts for the pixel it was taken
// in, with equal weight) and of the auxiliary first-hit quantities.
//
// Sums are kept in double with their squares, so the mean and the sample variance of each pixel are
// available (tests derive their tolerances from the latter). Each pixel is written by one task at a time
// and its samples are added in sample-index order, so the sums do not depend on thread scheduling.

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

  // The mean radiance per pixel (RGB).
  Image mean_image() const;
  // The variance of each pixel's mean (sample variance / n), RGB; 0 where n < 2.
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
  std::vector<glm::dvec3> normals_, albedo_, cost_;
  std::vector<double> depth_;
  std::vector<std::uint32_t> depth_hits_;
};

}  // namespace twinray
