#include "harness/crosscheck/hit_attributes.h"

#include <fmt/core.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace twinray::crosscheck {

namespace {

// The same constant as the arbiter's kWorld and the classifier's kAbsWorld (tolerances.h, hit_comparison.h).
constexpr double kWorld = kAbsWorld;

double max_abs(const glm::dvec3& p) { return std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}); }

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

AttributeRuling wrong(std::string detail) { return {false, std::move(detail)}; }

std::string vec_text(const glm::dvec3& v) { return fmt::format("({:.6g}, {:.6g}, {:.6g})", v.x, v.y, v.z); }

AttributeRuling rule_triangle(const TriangleMesh& mesh, const Ray& ray, const Hit& hit) {
  const glm::uvec3 tri = mesh.indices[hit.prim_id];
  const glm::dvec3 p0 = mesh.positions[tri[0]], p1 = mesh.positions[tri[1]], p2 = mesh.positions[tri[2]];
  const glm::dvec3 o = ray.org, d = ray.dir;
  const glm::dvec3 c = glm::cross(p1 - p0, p2 - p0);
  const double twice_area = glm::length(c);
  if (!(twice_area > 0.0)) return {};  // degenerate in double: no normal, no barycentrics to hold it to
  const glm::dvec3 n = c / twice_area;
  const double longest = std::max({glm::length(p1 - p0), glm::length(p2 - p1), glm::length(p0 - p2)});
  const double conditioning = longest * longest / twice_area;

  const glm::dvec3 ng = hit.ng;
  const double normal_tolerance = std::max(kNormalTolerance, kWorld * conditioning);
  if (glm::length(ng - n) > normal_tolerance)
    return wrong(fmt::format("ng {} is not normalize(cross(p1 - p0, p2 - p0)) = {} (off by {:.3g}, tolerance {:.3g})",
                             vec_text(ng), vec_text(n), glm::length(ng - n), normal_tolerance));

  // The ray's line crosses the plane at o + s d; parallel lines have no crossing to compare with.
  const double cos_angle = std::fabs(glm::dot(n, d)) / glm::length(d);
  if (!(cos_angle > 0.0)) return {};
  const double s = glm::dot(n, p0 - o) / glm::dot(n, d);
  const glm::dvec3 crossing = o + s * d;
  const double u = hit.u, v = hit.v;
  const glm::dvec3 point = (1.0 - u - v) * p0 + u * p1 + v * p2;
  const double scale = std::max({max_abs(p0), max_abs(p1), max_abs(p2), max_abs(o)});
  const double tolerance = kWorld * scale * conditioning / cos_angle;
  const double off = glm::length(point - crossing);
  if (!(off <= tolerance))
    return wrong(fmt::format("u {:.9g}, v {:.9g} name the point {}, {:.3g} away from where the ray crosses the "
                             "triangle, {} (tolerance {:.3g}; the point is (1-u-v) p0 + u p1 + v p2)",
                             hit.u, hit.v, vec_text(point), off, vec_text(crossing), tolerance));
  return {};
}

AttributeRuling rule_sphere(const Sphere& sphere, const Ray& ray, const Hit& hit) {
  const glm::dvec3 o = ray.org, d = ray.dir, center = sphere.center;
  const double r = sphere.radius;
  const glm::dvec3 p = o + static_cast<double>(hit.t) * d;
  const glm::dvec3 from_center = p - center;
  const double distance = glm::length(from_center);
  if (!(distance > 0.0) || !(r > 0.0)) return {};
  const glm::dvec3 n = from_center / distance;
  const double tolerance =
      std::max(kNormalTolerance, kWorld * (glm::length(o) + glm::length(p - o) + glm::length(center)) / r);
  const glm::dvec3 ng = hit.ng;
  if (glm::length(ng - n) > tolerance)
    return wrong(fmt::format("ng {} is not the outward normal {} at t (off by {:.3g}, tolerance {:.3g})", vec_text(ng),
                             vec_text(n), glm::length(ng - n), tolerance));
  if (!(hit.u >= 0.0f && hit.u <= 1.0f && hit.v >= 0.0f && hit.v <= 1.0f))
    return wrong(fmt::format("u {:.9g}, v {:.9g} are not in [0, 1] (u = atan2(n.z, n.x) / (2 pi) taken in [0, 1), "
                             "v = acos(n.y) / pi)",
                             hit.u, hit.v));
  const double theta = std::numbers::pi * hit.v, phi = 2.0 * std::numbers::pi * hit.u;
  const glm::dvec3 named(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
  if (glm::length(named - n) > tolerance)
    return wrong(fmt::format("u {:.9g}, v {:.9g} name the direction {}, not the outward normal {} at t (off by {:.3g}, "
                             "tolerance {:.3g}; u = atan2(n.z, n.x) / (2 pi) in [0, 1), v = acos(n.y) / pi)",
                             hit.u, hit.v, vec_text(named), vec_text(n), glm::length(named - n), tolerance));
  return {};
}

}  // namespace

AttributeRuling rule_attributes(const GeometryIndex& index, const Ray& ray, const Hit& hit) {
  if (!hit.found()) return {};
  if (!std::isfinite(hit.u) || !std::isfinite(hit.v) || !finite(hit.ng))
    return wrong(fmt::format("u {}, v {}, ng ({}, {}, {}): every attribute must be finite", hit.u, hit.v, hit.ng.x,
                             hit.ng.y, hit.ng.z));
  if (const TriangleMesh* mesh = index.mesh(hit.geom_id); mesh && hit.prim_id < mesh->indices.size())
    return rule_triangle(*mesh, ray, hit);
  if (const Sphere* sphere = index.sphere(hit.geom_id); sphere && hit.prim_id == 0) return rule_sphere(*sphere, ray, hit);
  return {};
}

}  // namespace twinray::crosscheck
