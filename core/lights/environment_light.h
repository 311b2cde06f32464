#pragma once
// Light arriving from infinitely far away: a constant radiance, or a latitude-longitude HDR image.
//
// Direction convention (world space, +Y up; see docs/environment.md):
//   theta = acos(dir.y) in [0, pi]: 0 = zenith (+Y) = top edge of the image, pi = nadir = bottom edge;
//           image row r covers theta in [r, r+1] * pi / height.
//   phi   = atan2(dir.x, -dir.z) in (-pi, pi]; image column coordinate u = 0.5 + phi / (2 pi) in [0,1):
//           the image centre column (u = 0.5) faces -Z, u = 0.75 faces +X, u = 0.25 faces -X and the left/
//           right edges (u = 0 / 1) face +Z. Seen from inside the sphere the image is not mirrored: facing -Z
//           with +X on your right, the image continues to the right.
//   rotation_deg rotates the map about +Y, positive = counter-clockwise seen from above (right-handed about
//           +Y): with 90 degrees, what the unrotated map showed towards +X is seen towards -Z.
// Lookup (Environment::filter):
//   nearest  (the default) radiance is piecewise constant per texel, which is exactly the function the
//            importance sampler is built for, so pdf(dir) is proportional to the luminance of eval(dir).
//   bilinear Mitsuba 3's envmap lookup: texel centres on a grid with u = (x + 0.5) / width, periodic, and
//            theta = y pi / (height - 1), first row at the zenith and last at the nadir; radiance is
//            interpolated bilinearly between the four centres around dir. Used for Mitsuba scenes and
//            wherever a map must look the same as in Mitsuba (docs/environment.md).
//
// Importance sampling (image maps only) works on a grid of sampling cells: the texels themselves for
// nearest, the width x (height - 1) bilinear patches between texel centres for bilinear. A cell is chosen
// with probability proportional to its luminance (the texel's; for a patch the mean of its four corners)
// times its solid angle (proportional to sin(theta) at the row centre), then a direction uniform in solid
// angle inside the cell. The resulting solid-angle density is constant per cell, with no 1/sin(theta)
// blow-up at the poles. For bilinear it is only roughly proportional to eval(dir), but positive wherever
// eval(dir) is (a patch with a bright corner has a positive weight), so the estimators stay unbiased.

#include "core/sampling/distribution_2d.h"
#include "core/scene/scene.h"

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/ext/vector_double3.hpp>

#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

namespace twinray {

class EnvironmentLight {
 public:
  // nullptr for EnvironmentType::None. Image maps are read through OpenImageIO; a missing or unreadable
  // file, a zero-size image, or a NaN / Inf / negative texel throws InputError(env.image, "texel (x, y)"
  // or "", message). `importance` = false samples the uniform sphere (for convergence comparisons);
  // importance tables are built only for image maps (a constant environment needs none).
  static std::unique_ptr<EnvironmentLight> create(const Environment& env, bool importance = true);

  // Radiance arriving from world direction dir (unit length), scale included.
  glm::vec3 eval(const glm::vec3& dir) const;

  struct Sample {
    glm::vec3 dir{0.0f};       // world direction towards the environment (unit)
    glm::vec3 radiance{0.0f};  // eval(dir)
    float pdf = 0.0f;          // w.r.t. solid angle; 0 => invalid sample, skip it
  };
  // u in [0,1)^2. The returned radiance and pdf are eval(dir) and pdf(dir) evaluated at the returned
  // direction, so they agree bit for bit with later eval/pdf calls (important for MIS).
  Sample sample(glm::vec2 u) const;
  // Solid-angle density with which sample() produces dir.
  float pdf(const glm::vec3& dir) const;

  // (1 / 4 pi) * integral of radiance over the sphere, scale included: the radiance of the constant
  // environment with the same power. For choosing between lights by power.
  glm::vec3 average_radiance() const;

  bool is_constant() const { return width_ == 0; }
  bool has_sampling_tables() const { return distribution_.has_value(); }
  std::size_t memory_bytes() const;
  int width() const { return width_; }   // texels; 0 for a constant environment
  int height() const { return height_; }

  EnvironmentFilter filter() const { return filter_; }
  // The map-space texel (column, row) whose cell contains world direction dir under nearest lookup
  // (rotation applied); for image maps. With bilinear lookup, the sampling cell (patch) instead: see cell_of.
  glm::ivec2 texel_of(const glm::vec3& dir) const;
  // The sampling cell (column, row) that contains world direction dir: the texel for nearest lookup, the
  // bilinear patch whose lower-left corner is texel (column, row) for bilinear lookup; for image maps.
  glm::ivec2 cell_of(const glm::vec3& dir) const;
  // Number of sampling cells per row and per column (width x height, or width x (height - 1)).
  glm::ivec2 cell_grid() const { return {width_, cell_rows_}; }
  // Solid angle of one sampling cell in row y.
  double cell_solid_angle(int y) const;
  // Radiance of texel (column, row), scale included; for image maps.
  glm::vec3 texel(int x, int y) const {
    return texels_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)];
  }
  // World direction of map coordinates (u, v) in [0,1]^2 (v = theta / pi, u as above), rotation applied.
  glm::vec3 direction_of(glm::vec2 uv) const;
  // Solid angle of one texel in row y (all texels of a row have the same one).
  double texel_solid_angle(int y) const;

 private:
  EnvironmentLight() = default;

  friend glm::dvec3 environment_irradiance(const EnvironmentLight&, glm::vec3, int);

  // World direction -> unrotated map coordinates (u, v) in [0,1]^2.
  glm::vec2 map_uv(const glm::vec3& dir) const;
  // Row-major index of the cell cell_of(dir) (for nearest lookup also the texel's index).
  std::size_t cell_index(const glm::vec3& dir) const;
  // Radiance at unrotated map coordinates (u, v) under bilinear lookup.
  glm::vec3 bilinear(glm::vec2 uv) const;
  // World direction for map-space azimuth phi_map (phi of the unrotated map) and cos(theta).
  glm::vec3 world_direction(double phi_map, double cos_theta) const;

  glm::vec3 constant_{0.0f};                   // constant environments: radiance * scale
  int width_ = 0, height_ = 0;                 // 0 x 0 for constant environments
  std::vector<glm::vec3> texels_;              // radiance * scale, row-major, top row (zenith) first
  float rotation_u_ = 0.0f;                    // rotation_deg / 360: map u = world u + rotation_u_ (mod 1)
  EnvironmentFilter filter_ = EnvironmentFilter::Nearest;
  // Sampling cells: width_ columns starting at map u = cell_u0_ (0, or half a texel for bilinear patches),
  // cell_rows_ rows (height_, or height_ - 1 for bilinear patches).
  float cell_u0_ = 0.0f;
  int cell_rows_ = 0;
  std::vector<double> row_cos_;                // cos(theta) at the cell_rows_ + 1 cell row edges
  std::optional<Distribution2D> distribution_; // importance tables (image maps with importance = true)
  // Solid-angle pdf of every cell, pmf / cell solid angle, row-major: pdf() is one load, no search
  // through the distribution (MIS evaluates it for every BSDF-sampled ray that escapes).
  std::vector<float> cell_pdf_;
  glm::vec3 average_{0.0f};
};

// Irradiance E(n) = integral over the hemisphere around `normal` of L(w) max(0, n.w) dw, by direct
// quadrature over the texels (each texel split into subdivisions x subdivisions cells, equal in solid
// angle; one evaluation at each cell's centre in (phi, cos theta)), in double. Independent of the sampling
// code, so tests of the renderer can compare against it: a white Lambertian plane facing n has outgoing
// radiance E(n) / pi. Constant environments are integrated on a 64 x 32 virtual grid (result pi * L up to
// the quadrature error at the horizon; exact when n = +Y or -Y because the horizon is a row edge). With
// bilinear lookup the cells subdivide the sampling cells (patches) and the radiance is evaluated at each
// cell's centre: the midpoint rule, second-order accurate in the cell size.
glm::dvec3 environment_irradiance(const EnvironmentLight& light, glm::vec3 normal, int subdivisions = 4);

}  // namespace twinray
