#include "core/lights/environment_light.h"

#include "core/image/image_io.h"
#include "core/sampling/warp.h"
#include "core/util/input_error.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace twinray {

namespace {

constexpr double kPiD = std::numbers::pi;

// Rec. 709 / sRGB primaries: the importance weight. Any positive combination would be unbiased; this
// one matches perceived brightness, which is what the variance we care about is measured in.
float luminance(const glm::vec3& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

bool finite_non_negative(const glm::vec3& c) {
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(c[i]) || c[i] < 0.0f) return false;
  return true;
}

// Solid angle of a cell in row y of a grid of `columns` x `rows` cells equal in (phi, theta) extent:
// (2 pi / columns) * (cos theta0 - cos theta1) = (2 pi / columns) * 2 sin(theta_centre) sin(dtheta / 2).
// The product form has no cancellation next to the poles, where the two cosines are nearly equal. For
// nearest lookup the cells are the texels; for bilinear lookup the patches between texel centres.
double lat_long_texel_solid_angle(int y, int columns, int rows) {
  const double dtheta = kPiD / static_cast<double>(rows);
  const double theta_centre = (static_cast<double>(y) + 0.5) * dtheta;
  return (2.0 * kPiD / static_cast<double>(columns)) * 2.0 * std::sin(theta_centre) * std::sin(0.5 * dtheta);
}

// cos(theta) at the rows + 1 row edges; the ends are exact (+1 at the zenith, -1 at the nadir).
std::vector<double> lat_long_row_edge_cosines(int rows) {
  std::vector<double> c(static_cast<std::size_t>(rows) + 1);
  for (int r = 0; r <= rows; ++r) c[static_cast<std::size_t>(r)] = std::cos(kPiD * r / rows);
  c.front() = 1.0;
  c.back() = -1.0;
  return c;
}

std::string texel_name(int x, int y) { return "texel (" + std::to_string(x) + ", " + std::to_string(y) + ")"; }

}  // namespace

std::unique_ptr<EnvironmentLight> EnvironmentLight::create(const Environment& env, bool importance) {
  if (env.type == EnvironmentType::None) return nullptr;
  const std::filesystem::path& file = env.image;
  if (!std::isfinite(env.scale) || env.scale < 0.0f)
    throw InputError(file, "", "environment scale must be finite and >= 0");

  std::unique_ptr<EnvironmentLight> light(new EnvironmentLight());
  if (env.type == EnvironmentType::Constant) {
    if (!finite_non_negative(env.radiance))
      throw InputError(file, "", "constant environment radiance must be finite and >= 0");
    light->constant_ = env.radiance * env.scale;
    light->average_ = light->constant_;
    return light;  // no texels, no tables
  }

  const Image image = env.pixels ? *env.pixels : read_image(file);  // throws InputError naming the file
  const int w = image.width, h = image.height;
  light->width_ = w;
  light->height_ = h;
  light->texels_.resize(image.pixel_count());
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      glm::vec3 c;
      if (image.channels >= 3) {
        c = glm::vec3(image.at(x, y, 0), image.at(x, y, 1), image.at(x, y, 2));
      } else {
        c = glm::vec3(image.at(x, y, 0));  // grey, or grey + alpha (alpha ignored)
      }
      for (int i = 0; i < 3; ++i) {
        if (std::isnan(c[i])) throw InputError(file, texel_name(x, y), "radiance is NaN");
        if (std::isinf(c[i])) throw InputError(file, texel_name(x, y), "radiance is infinite");
        if (c[i] < 0.0f) throw InputError(file, texel_name(x, y), "radiance is negative");
      }
      light->texels_[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)] =
          c * env.scale;
    }
  }

  const double turns = static_cast<double>(env.rotation_deg) / 360.0;
  light->rotation_u_ = static_cast<float>(turns - std::floor(turns));
  if (light->rotation_u_ >= 1.0f) light->rotation_u_ = 0.0f;  // -tiny wrapped to 1 - tiny, rounded to 1
  light->filter_ = env.filter;
  const bool bilinear = env.filter == EnvironmentFilter::Bilinear;
  if (bilinear && h < 2)
    throw InputError(file, "", "bilinear lookup needs a map at least 2 texels high (one row at each pole)");
  light->cell_rows_ = bilinear ? h - 1 : h;
  light->cell_u0_ = bilinear ? 0.5f / static_cast<float>(w) : 0.0f;
  light->row_cos_ = lat_long_row_edge_cosines(light->cell_rows_);

  // The luminance (or the radiance, for the power) that stands for cell (x, y): the texel itself, or for
  // a bilinear patch the mean of its four corners, which is the exact mean of the bilinear function over
  // the patch in (u, v) (the sin(theta) weighting within the patch is left out: a cell weight needs only
  // to be positive wherever the radiance is, and the average radiance only to rank lights by power).
  const auto cell_radiance = [&](int x, int y) -> glm::vec3 {
    if (!bilinear) return light->texel(x, y);
    const int x1 = (x + 1) % w;
    return 0.25f * (light->texel(x, y) + light->texel(x1, y) + light->texel(x, y + 1) + light->texel(x1, y + 1));
  };
  const int rows = light->cell_rows_;
  glm::dvec3 power(0.0);
  for (int y = 0; y < rows; ++y) {
    const double solid_angle = lat_long_texel_solid_angle(y, w, rows);
    for (int x = 0; x < w; ++x) power += glm::dvec3(cell_radiance(x, y)) * solid_angle;
  }
  light->average_ = glm::vec3(power / (4.0 * kPiD));

  if (importance) {
    // Weight = luminance x cell solid angle, i.e. the cell's share of the luminous power arriving from
    // the sphere. The solid angle (proportional to sin(theta) at the row centre) undoes the over-
    // representation of the poles in a lat-long image: a texel row near the zenith covers far less of the
    // sphere than one at the horizon although both have `width` texels.
    const std::size_t cells = static_cast<std::size_t>(w) * static_cast<std::size_t>(rows);
    std::vector<float> weights(cells);
    for (int y = 0; y < rows; ++y) {
      const double solid_angle = lat_long_texel_solid_angle(y, w, rows);
      for (int x = 0; x < w; ++x)
        weights[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)] =
            static_cast<float>(static_cast<double>(luminance(cell_radiance(x, y))) * solid_angle);
    }
    const Distribution2D& distribution = light->distribution_.emplace(weights, w, rows);
    light->cell_pdf_.resize(cells);
    for (int y = 0; y < rows; ++y) {
      const double inverse_solid_angle = 1.0 / lat_long_texel_solid_angle(y, w, rows);
      for (int x = 0; x < w; ++x)
        light->cell_pdf_[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)] =
            static_cast<float>(static_cast<double>(distribution.pmf(x, y)) * inverse_solid_angle);
    }
  }
  return light;
}

glm::vec2 EnvironmentLight::map_uv(const glm::vec3& dir) const {
  const float theta = std::acos(std::clamp(dir.y, -1.0f, 1.0f));
  const float phi = std::atan2(dir.x, -dir.z);
  float u = 0.5f + phi * kInv2Pi + rotation_u_;
  u -= std::floor(u);
  return glm::vec2(u, theta * kInvPi);
}

glm::ivec2 EnvironmentLight::texel_of(const glm::vec3& dir) const {
  const glm::vec2 uv = map_uv(dir);
  const int x = std::min(static_cast<int>(uv.x * static_cast<float>(width_)), width_ - 1);
  const int y = std::min(static_cast<int>(uv.y * static_cast<float>(height_)), height_ - 1);
  return glm::ivec2(std::max(x, 0), std::max(y, 0));
}

glm::ivec2 EnvironmentLight::cell_of(const glm::vec3& dir) const {
  glm::vec2 uv = map_uv(dir);
  uv.x -= cell_u0_;
  uv.x -= std::floor(uv.x);
  const int x = std::min(static_cast<int>(uv.x * static_cast<float>(width_)), width_ - 1);
  const int y = std::min(static_cast<int>(uv.y * static_cast<float>(cell_rows_)), cell_rows_ - 1);
  return glm::ivec2(std::max(x, 0), std::max(y, 0));
}

std::size_t EnvironmentLight::cell_index(const glm::vec3& dir) const {
  const glm::ivec2 t = cell_of(dir);
  return static_cast<std::size_t>(t.y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(t.x);
}

glm::vec3 EnvironmentLight::bilinear(glm::vec2 uv) const {
  // Texel centres sit at u = (x + 0.5) / width and v = y / (height - 1): shift by half a texel in u (the
  // grid wraps around), scale to texel units, split into the patch corner and the weights inside it.
  float fu = uv.x - cell_u0_;
  fu -= std::floor(fu);
  fu *= static_cast<float>(width_);
  const float fv = uv.y * static_cast<float>(height_ - 1);
  const int x0 = std::clamp(static_cast<int>(fu), 0, width_ - 1);
  const int y0 = std::clamp(static_cast<int>(fv), 0, height_ - 2);
  const int x1 = x0 + 1 == width_ ? 0 : x0 + 1;
  const float wu = std::clamp(fu - static_cast<float>(x0), 0.0f, 1.0f);
  const float wv = std::clamp(fv - static_cast<float>(y0), 0.0f, 1.0f);
  const glm::vec3 top = (1.0f - wu) * texel(x0, y0) + wu * texel(x1, y0);
  const glm::vec3 bottom = (1.0f - wu) * texel(x0, y0 + 1) + wu * texel(x1, y0 + 1);
  return (1.0f - wv) * top + wv * bottom;
}

glm::vec3 EnvironmentLight::world_direction(double phi_map, double cos_theta) const {
  // Map u = world u + rotation_u_, so world phi = map phi - 2 pi rotation_u_.
  const double phi = phi_map - 2.0 * kPiD * static_cast<double>(rotation_u_);
  const double sin_theta = std::sqrt(std::max(0.0, (1.0 - cos_theta) * (1.0 + cos_theta)));
  return glm::vec3(static_cast<float>(sin_theta * std::sin(phi)), static_cast<float>(cos_theta),
                   static_cast<float>(-sin_theta * std::cos(phi)));
}

glm::vec3 EnvironmentLight::direction_of(glm::vec2 uv) const {
  const double phi_map = 2.0 * kPiD * (static_cast<double>(uv.x) - 0.5);
  return world_direction(phi_map, std::cos(kPiD * static_cast<double>(uv.y)));
}

double EnvironmentLight::texel_solid_angle(int y) const { return lat_long_texel_solid_angle(y, width_, height_); }

double EnvironmentLight::cell_solid_angle(int y) const { return lat_long_texel_solid_angle(y, width_, cell_rows_); }

glm::vec3 EnvironmentLight::eval(const glm::vec3& dir) const {
  if (is_constant()) return constant_;
  if (filter_ == EnvironmentFilter::Bilinear) return bilinear(map_uv(dir));
  return texels_[cell_index(dir)];
}

float EnvironmentLight::pdf(const glm::vec3& dir) const {
  if (!distribution_) return uniform_sphere_pdf();
  return cell_pdf_[cell_index(dir)];
}

EnvironmentLight::Sample EnvironmentLight::sample(glm::vec2 u) const {
  Sample s;
  if (!distribution_) {
    s.dir = sample_uniform_sphere(u);
  } else {
    glm::vec2 in_cell(0.0f);
    const glm::ivec2 t = distribution_->sample_cell(u, nullptr, &in_cell);
    // Uniform in solid angle inside the cell: uniform in phi and in cos(theta) across the row's band.
    const double phi_map =
        2.0 * kPiD * ((static_cast<double>(t.x) + static_cast<double>(in_cell.x)) / width_ +
                      static_cast<double>(cell_u0_) - 0.5);
    const double c0 = row_cos_[static_cast<std::size_t>(t.y)], c1 = row_cos_[static_cast<std::size_t>(t.y) + 1];
    const double cos_theta = c0 + static_cast<double>(in_cell.y) * (c1 - c0);
    s.dir = world_direction(phi_map, cos_theta);
  }
  // Evaluated at the returned direction (not taken from the chosen cell): float rounding can move a
  // sample drawn next to a cell edge into the neighbour, and MIS needs sample() and pdf() to agree.
  if (is_constant()) {
    s.radiance = constant_;
    s.pdf = uniform_sphere_pdf();
    return s;
  }
  const std::size_t i = cell_index(s.dir);
  s.radiance = filter_ == EnvironmentFilter::Bilinear ? bilinear(map_uv(s.dir)) : texels_[i];
  s.pdf = distribution_ ? cell_pdf_[i] : uniform_sphere_pdf();
  return s;
}

glm::vec3 EnvironmentLight::average_radiance() const { return average_; }

std::size_t EnvironmentLight::memory_bytes() const {
  std::size_t bytes = sizeof(*this) + texels_.capacity() * sizeof(glm::vec3) +
                      row_cos_.capacity() * sizeof(double) + cell_pdf_.capacity() * sizeof(float);
  if (distribution_) bytes += distribution_->memory_bytes();
  return bytes;
}

glm::dvec3 environment_irradiance(const EnvironmentLight& light, glm::vec3 normal, int subdivisions) {
  const int k = std::max(subdivisions, 1);
  // Constant environments have no texels: integrate them on a virtual grid of this size. Image maps are
  // integrated over their sampling cells (texels, or bilinear patches starting half a texel in).
  const int w = light.is_constant() ? 64 : light.width();
  const int h = light.is_constant() ? 32 : light.cell_rows_;
  const double u0 = light.is_constant() ? 0.0 : static_cast<double>(light.cell_u0_);
  const bool per_texel = light.is_constant() || light.filter_ == EnvironmentFilter::Nearest;
  const glm::dvec3 n = glm::normalize(glm::dvec3(normal));

  // Cell centres in (phi, cos theta): both coordinates are uniform in solid angle (dw = dphi dcos), so
  // equal steps give cells of equal solid angle and the midpoint rule is exact for integrands linear in
  // cos theta, e.g. the cosine for n = +-Y.
  const int columns = w * k;
  std::vector<double> sin_phi(static_cast<std::size_t>(columns)), cos_phi(static_cast<std::size_t>(columns));
  for (int i = 0; i < columns; ++i) {
    const double phi_map = 2.0 * kPiD * ((i + 0.5) / columns + u0 - 0.5);
    const double phi = phi_map - 2.0 * kPiD * static_cast<double>(light.rotation_u_);
    sin_phi[static_cast<std::size_t>(i)] = std::sin(phi);
    cos_phi[static_cast<std::size_t>(i)] = std::cos(phi);
  }
  const std::vector<double> row_cos = lat_long_row_edge_cosines(h);
  const double dphi = 2.0 * kPiD / columns;

  glm::dvec3 total(0.0);
  for (int y = 0; y < h; ++y) {
    const double c0 = row_cos[static_cast<std::size_t>(y)], c1 = row_cos[static_cast<std::size_t>(y) + 1];
    const double dcos = (c0 - c1) / k;
    for (int j = 0; j < k; ++j) {
      const double z = c0 - (j + 0.5) * dcos;
      const double s = std::sqrt(std::max(0.0, (1.0 - z) * (1.0 + z)));
      for (int x = 0; x < w; ++x) {
        if (per_texel) {
          double cos_sum = 0.0;  // sum of clamped cosines over this texel's cells in the sub-row
          for (int i = x * k; i < (x + 1) * k; ++i) {
            const glm::dvec3 dir(s * sin_phi[static_cast<std::size_t>(i)], z, -s * cos_phi[static_cast<std::size_t>(i)]);
            cos_sum += std::max(0.0, glm::dot(n, dir));
          }
          if (cos_sum > 0.0) {
            const glm::vec3 radiance = light.is_constant() ? light.constant_ : light.texel(x, y);
            total += glm::dvec3(radiance) * (cos_sum * dphi * dcos);
          }
          continue;
        }
        for (int i = x * k; i < (x + 1) * k; ++i) {
          const glm::dvec3 dir(s * sin_phi[static_cast<std::size_t>(i)], z, -s * cos_phi[static_cast<std::size_t>(i)]);
          const double cosine = glm::dot(n, dir);
          if (cosine > 0.0) total += glm::dvec3(light.eval(glm::vec3(dir))) * (cosine * dphi * dcos);
        }
      }
    }
  }
  return total;
}

}  // namespace twinray
