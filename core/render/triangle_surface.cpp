#include "core/render/triangle_surface.h"

#include "core/intersect/triangle_watertight.h"

#include <glm/common.hpp>

#include <cmath>

namespace twinray {
namespace {

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

TriangleSurface TriangleSurface::make(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2) {
  TriangleSurface s;
  s.p0 = p0;
  s.e1 = p1 - p0;
  s.e2 = p2 - p0;
  const glm::vec3 m = glm::max(glm::abs(p0), glm::max(glm::abs(p1), glm::abs(p2)));
  s.error_scale = std::max(m.x, std::max(m.y, m.z));
  s.ng = triangle_geometric_normal(p0, p1, p2);
  // In double from the float vertices: the rows are then correctly rounded up to a few ulps, also for
  // triangles whose float cross product would lose digits.
  const glm::dvec3 a = glm::dvec3(p0), e1 = glm::dvec3(p1) - a, e2 = glm::dvec3(p2) - a;
  const glm::dvec3 n = glm::cross(e1, e2);
  const double n2 = glm::dot(n, n);
  if (!(n2 > 0.0) || !std::isfinite(n2)) return s;  // collinear vertices: never hit; the point is p0
  const glm::vec3 to_u(glm::cross(e2, n) / n2), to_v(glm::cross(n, e1) / n2);
  // A sliver far below float's range overflows them: its points are p0 then, within its own size.
  if (!finite(to_u) || !finite(to_v)) return s;
  s.to_u = to_u;
  s.to_v = to_v;
  return s;
}

}  // namespace twinray
