#include "core/scene/transform.h"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

namespace twinray {

AffineTransform AffineTransform::scale_rotate_translate(const glm::dvec3& scale, const glm::dvec3& axis,
                                                        double angle_deg, const glm::dvec3& translate) {
  const glm::dvec3 a = glm::normalize(axis);
  const double theta = angle_deg * (std::numbers::pi / 180.0);
  const double c = std::cos(theta), s = std::sin(theta), t = 1.0 - c;
  // Rodrigues' rotation formula; glm matrices are column-major, so each dvec3 below is a column.
  const glm::dmat3 rotation(glm::dvec3(t * a.x * a.x + c, t * a.x * a.y + s * a.z, t * a.x * a.z - s * a.y),
                            glm::dvec3(t * a.x * a.y - s * a.z, t * a.y * a.y + c, t * a.y * a.z + s * a.x),
                            glm::dvec3(t * a.x * a.z + s * a.y, t * a.y * a.z - s * a.x, t * a.z * a.z + c));
  const glm::dmat3 scaling(glm::dvec3(scale.x, 0, 0), glm::dvec3(0, scale.y, 0), glm::dvec3(0, 0, scale.z));
  AffineTransform result;
  result.linear = rotation * scaling;
  result.translation = translate;
  return result;
}

double AffineTransform::determinant() const { return glm::determinant(linear); }

std::optional<double> AffineTransform::uniform_scale() const {
  // Relative tolerance for "equal lengths" and "orthogonal": 1e-5 accepts a rotation matrix printed with
  // float precision, while a real non-uniform scale (even 1.001 vs 1) is rejected.
  constexpr double kTolerance = 1e-5;
  const double l0 = glm::length(linear[0]), l1 = glm::length(linear[1]), l2 = glm::length(linear[2]);
  const double s = (l0 + l1 + l2) / 3.0;
  if (!(s > 0.0) || !std::isfinite(s)) return std::nullopt;
  if (std::abs(l0 - s) > kTolerance * s || std::abs(l1 - s) > kTolerance * s || std::abs(l2 - s) > kTolerance * s)
    return std::nullopt;
  const double s2 = s * s;
  if (std::abs(glm::dot(linear[0], linear[1])) > kTolerance * s2 ||
      std::abs(glm::dot(linear[1], linear[2])) > kTolerance * s2 ||
      std::abs(glm::dot(linear[0], linear[2])) > kTolerance * s2)
    return std::nullopt;
  return s;
}

void transform_mesh(TriangleMesh& mesh, const AffineTransform& transform) {
  for (glm::vec3& p : mesh.positions) p = glm::vec3(transform.apply_point(glm::dvec3(p)));
  if (transform.flips_orientation())
    for (glm::uvec3& tri : mesh.indices) std::swap(tri[1], tri[2]);
}

void transform_sphere(Sphere& sphere, const AffineTransform& transform) {
  const std::optional<double> scale = transform.uniform_scale();
  if (!scale) throw std::invalid_argument("a sphere only accepts a uniform scale (no non-uniform scale or shear)");
  sphere.center = glm::vec3(transform.apply_point(glm::dvec3(sphere.center)));
  sphere.radius = static_cast<float>(*scale * static_cast<double>(sphere.radius));
}

}  // namespace twinray
