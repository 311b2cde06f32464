#pragma once
// Affine placement of a shape in the scene (the JSON "transform" object), evaluated in double precision so
// that composing scale, rotation and translation adds no float rounding before the final vertex store.

#include "core/geometry/scene_geometry.h"

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <optional>

namespace twinray {

struct AffineTransform {
  glm::dmat3 linear{1.0};
  glm::dvec3 translation{0.0};

  // Scale first, then rotate by `angle_deg` degrees about `axis` (right-handed: counter-clockwise when the
  // axis points at the viewer), then translate. `axis` must be non-zero; it need not be normalised.
  static AffineTransform scale_rotate_translate(const glm::dvec3& scale, const glm::dvec3& axis, double angle_deg,
                                                const glm::dvec3& translate);

  glm::dvec3 apply_point(const glm::dvec3& p) const { return linear * p + translation; }
  double determinant() const;
  // A mirroring transform turns counter-clockwise triangles clockwise.
  bool flips_orientation() const { return determinant() < 0.0; }
  // The factor s when `linear` is s times a rotation (or reflection), within the precision a matrix written
  // with float precision (about 7 significant digits) can have; nullopt for a non-uniform scale or shear.
  std::optional<double> uniform_scale() const;
};

// Moves every vertex and, when the transform mirrors, reverses each triangle's winding so that the front
// side (the side emissive surfaces light) stays the same side of the surface. Vertices may become
// non-finite if the transform overflows float: callers check (see all_positions_finite).
void transform_mesh(TriangleMesh& mesh, const AffineTransform& transform);

// Spheres only support transforms that keep them spheres: throws std::invalid_argument otherwise.
void transform_sphere(Sphere& sphere, const AffineTransform& transform);

}  // namespace twinray
