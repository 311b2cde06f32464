#include "harness/arbiter/candidates.h"

#include "core/exact/exact_number.h"
#include "core/exact/exact_sphere.h"
#include "core/exact/exact_triangle.h"
#include "harness/arbiter/tolerances.h"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace twinray::arbiter {

namespace {

double max_abs(const glm::dvec3& v) { return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}); }

// An orthonormal frame whose third axis is the ray's direction: distances from the line are 2D distances
// from the origin of the (u, v) plane. Double precision: these classify for a tolerance of ~170 float ulps.
struct Frame {
  glm::dvec3 u, v, w;
};

Frame frame_along(const glm::dvec3& d) {
  Frame f;
  f.w = glm::normalize(d);
  const glm::dvec3 helper = std::fabs(f.w.x) < 0.9 ? glm::dvec3(1.0, 0.0, 0.0) : glm::dvec3(0.0, 1.0, 0.0);
  f.u = glm::normalize(glm::cross(f.w, helper));
  f.v = glm::cross(f.w, f.u);
  return f;
}

glm::dvec2 project(const glm::dvec3& p, const glm::dvec3& o, const Frame& f) {
  const glm::dvec3 r = p - o;
  return {glm::dot(r, f.u), glm::dot(r, f.v)};
}

double cross2(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

// Distance from the 2D origin to segment [a, b].
double segment_distance(const glm::dvec2& a, const glm::dvec2& b) {
  const glm::dvec2 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double s = len2 > 0.0 ? std::clamp(-glm::dot(a, ab) / len2, 0.0, 1.0) : 0.0;
  return glm::length(a + s * ab);
}

// The exact decisions run on the float values, read through their bits.
void evaluate_triangle(const TriangleMesh& mesh, std::uint32_t prim, const Ray& ray, const glm::dvec3& o,
                       const glm::dvec3& d, const Frame& frame, Candidate& c) {
  const glm::uvec3& tri = mesh.indices[prim];
  glm::dvec3 p[3];
  for (int k = 0; k < 3; ++k) {
    c.vertex[k] = mesh.positions[tri[k]];
    p[k] = exact::to_double_exact(c.vertex[k]);
  }
  c.scale = std::max({max_abs(o), max_abs(p[0]), max_abs(p[1]), max_abs(p[2])});
  c.delta = kWorld * c.scale;
  const glm::dvec2 q[3] = {project(p[0], o, frame), project(p[1], o, frame), project(p[2], o, frame)};
  double boundary = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const double e = segment_distance(q[k], q[(k + 1) % 3]);
    boundary = std::min(boundary, e);
    if (e <= c.delta) c.near_edges |= 1u << k;
  }
  const double s0 = cross2(q[1], q[2]), s1 = cross2(q[2], q[0]), s2 = cross2(q[0], q[1]);
  const bool inside = (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0);
  c.distance = inside ? 0.0 : boundary;
  c.near_boundary = c.near_edges != 0;
  if (!c.reachable()) return;
  const exact::TriangleCrossing x = exact::intersect_triangle_exact({o, d, p[0], p[1], p[2]});
  c.crossing = !x.parallel && std::isfinite(x.t);
  c.t = x.t;
  c.t_exact = x.t_double;
  c.hit = x.hit && c.crossing && c.t >= ray.tmin && c.t <= ray.tmax;
  if (c.crossing) {  // tolerances.h, kGrazeT
    const glm::dvec3 n = glm::cross(p[1] - p[0], p[2] - p[0]);
    const double twice_area = glm::length(n), d_length = glm::length(d);
    const double longest2 = std::max({glm::dot(p[1] - p[0], p[1] - p[0]), glm::dot(p[2] - p[1], p[2] - p[1]),
                                      glm::dot(p[0] - p[2], p[0] - p[2])});
    const double cos_abs = std::fabs(glm::dot(n, d)) / (twice_area * d_length);
    if (twice_area > 0.0 && cos_abs > 0.0) c.graze_t = kGrazeT * c.scale * (longest2 / twice_area) / (cos_abs * d_length);
  }
}

void evaluate_sphere(const Sphere& s, const Ray& ray, const glm::dvec3& o, const glm::dvec3& d, Candidate& c) {
  c.sphere = true;
  c.vertex[0] = s.center;
  c.vertex[1] = glm::vec3(s.radius, 0.0f, 0.0f);
  const glm::dvec3 center = exact::to_double_exact(s.center);
  const double r = exact::to_double_exact(s.radius);
  c.scale = std::max(max_abs(o), max_abs(center) + r);
  c.delta = kWorld * c.scale;
  const glm::dvec3 f = o - center;
  const double closest_t = -glm::dot(f, d) / glm::dot(d, d);
  const double line_distance = glm::length(f + closest_t * d);
  c.distance = std::max(0.0, line_distance - r);
  c.near_boundary = std::fabs(line_distance - r) <= c.delta;
  if (!c.reachable()) return;
  if (c.near_boundary) {
    const double grown = r + c.delta;
    const double half = std::sqrt(std::max(0.0, grown * grown - line_distance * line_distance)) / glm::length(d);
    c.graze_lo = closest_t - half * (1.0 + 1e-9) - 1e-300;
    c.graze_hi = closest_t + half * (1.0 + 1e-9) + 1e-300;
  }
  const exact::SphereCrossing x = exact::intersect_sphere_exact({o, d, center, r});
  if (!x.real) return;
  c.crossing = true;
  const auto in_interval = [&ray](float t) { return std::isfinite(t) && t >= ray.tmin && t <= ray.tmax; };
  const bool take_far = !in_interval(x.t_near) && in_interval(x.t_far);
  c.hit = in_interval(x.t_near) || take_far;
  c.t = take_far ? x.t_far : x.t_near;
  c.t_exact = take_far ? x.far_double : x.near_double;
  c.t_other = take_far ? x.near_double : x.far_double;
}

}  // namespace

double Candidate::t_tolerance(double dir_length) const {
  return kRelT * std::fabs(t_exact) + std::max(kWorld * scale / dir_length, graze_t);
}

ShapeIndex::ShapeIndex(const SceneGeometry& geometry) {
  const std::uint32_t end = geometry.geom_id_end();
  meshes_.assign(end, nullptr);
  spheres_.assign(end, nullptr);
  for (const TriangleMesh& m : geometry.meshes) {
    meshes_[m.geom_id] = &m;
    for (const glm::uvec3& tri : m.indices)
      for (int k = 0; k < 3; ++k) max_coordinate_ = std::max(max_coordinate_, max_abs(glm::dvec3(m.positions[tri[k]])));
  }
  for (const Sphere& s : geometry.spheres) {
    spheres_[s.geom_id] = &s;
    max_coordinate_ = std::max(max_coordinate_, max_abs(glm::dvec3(s.center)) + std::fabs(double(s.radius)));
  }
}

Candidate evaluate_primitive(const ShapeIndex& shapes, const Ray& ray, PrimitiveRef ref, bool& ok) {
  const glm::dvec3 o = exact::to_double_exact(ray.org), d = exact::to_double_exact(ray.dir);
  Candidate c;
  c.ref = ref;
  ok = true;
  const TriangleMesh* mesh = shapes.mesh(ref.geom_id);
  if (mesh != nullptr && ref.prim_id < mesh->indices.size()) {
    evaluate_triangle(*mesh, ref.prim_id, ray, o, d, frame_along(d), c);
  } else if (const Sphere* sphere = shapes.sphere(ref.geom_id); sphere != nullptr && ref.prim_id == 0) {
    evaluate_sphere(*sphere, ray, o, d, c);
  } else {
    ok = false;
  }
  return c;
}

std::vector<Candidate> near_candidates(const ExactBackend& exact, const ShapeIndex& shapes, const Ray& ray) {
  const glm::dvec3 o = exact::to_double_exact(ray.org), d = exact::to_double_exact(ray.dir);
  const double dir_length = glm::length(d);
  const double max_scale = std::max(max_abs(o), shapes.max_coordinate());
  // The search region: every primitive's delta and t tolerance are at most these.
  const double margin = kWorld * max_scale;
  const double t_slack = kWorld * max_scale / dir_length;
  const double t_lo = ray.tmin - kRelT * std::fabs(ray.tmin) - t_slack;
  const double t_hi = std::isfinite(ray.tmax) ? ray.tmax + kRelT * std::fabs(ray.tmax) + t_slack
                                              : std::numeric_limits<double>::infinity();
  std::vector<PrimitiveRef> refs;
  exact.primitives_near(ray, margin, t_lo, t_hi, refs);

  const Frame frame = frame_along(d);
  std::vector<Candidate> out;
  out.reserve(refs.size());
  for (const PrimitiveRef& ref : refs) {
    Candidate c;
    c.ref = ref;
    if (const TriangleMesh* mesh = shapes.mesh(ref.geom_id)) evaluate_triangle(*mesh, ref.prim_id, ray, o, d, frame, c);
    else if (const Sphere* sphere = shapes.sphere(ref.geom_id)) evaluate_sphere(*sphere, ray, o, d, c);
    else continue;
    if (c.reachable()) out.push_back(c);
  }
  return out;
}

}  // namespace twinray::arbiter
