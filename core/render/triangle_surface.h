#pragma once
// The surface point of a triangle hit from the ray and its t alone, from numbers prepared once per triangle.
//
// Why: the renderer needs the hit point, the geometric normal and the error scale of the point's
// coordinates, never the barycentrics themselves. A closest-hit query that certifies u and v (correctly
// rounded, triangle_refine.h) and normalises the normal in double spends about a fifth of its work on them
// (docs/rendering.md); the renderer asks Backend::intersect_ids for t and the ids only and finishes here.
//
// The point: q = org + t dir, with t the correctly rounded crossing parameter every exact backend reports,
// lies within a few ulps of |org| + t |dir| of the true crossing. Its barycentrics u = (q - p0).to_u,
// v = (q - p0).to_v (to_u, to_v: the rows of the inverse of the edge matrix on the triangle's plane, so the
// component of q - p0 off the plane drops out) are clamped to the triangle, and the point is rebuilt from
// them as p0 + u e1 + v e2. That puts it in the triangle's plane up to ulps of the vertex coordinates, the
// error model of the ray offsets (ray_offset.h, error_scale below), and inside the triangle, as the
// certified barycentrics did; it differs from the certified point only by the in-plane rounding of q
// (relative 1e-7 of the ray's length), far below a pixel's footprint, so images have the same expectation.
// Every backend that reports the same t and ids (bvh8, bvh, brute: tests/test_render_backends_agree.cpp)
// gives the same point, bit for bit, since nothing here comes from the backend but t and the ids.
//
// The normal is triangle_geometric_normal's: the same bits as a closest-hit query reports in Hit::ng.

#include "core/geometry/ray.h"

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>

namespace twinray {

struct TriangleSurface {
  glm::vec3 p0{0.0f};
  float error_scale = 0.0f;          // largest vertex coordinate magnitude: what the point's error scales with
  glm::vec3 e1{0.0f}, e2{0.0f};      // p1 - p0, p2 - p0
  glm::vec3 to_u{0.0f}, to_v{0.0f};  // (e2 x n) / |n|^2, (n x e1) / |n|^2 with n = e1 x e2 (0 if degenerate)
  glm::vec3 ng{0.0f};                // unit geometric normal, triangle_geometric_normal's bits

  static TriangleSurface make(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2);

  // The hit point of `ray` at its crossing parameter t with this triangle (see above).
  glm::vec3 point(const Ray& ray, float t) const {
    const glm::vec3 d = (ray.org + t * ray.dir) - p0;
    const float u = std::clamp(glm::dot(d, to_u), 0.0f, 1.0f);
    const float v = std::clamp(glm::dot(d, to_v), 0.0f, 1.0f - u);
    return p0 + u * e1 + v * e2;
  }
};

}  // namespace twinray
