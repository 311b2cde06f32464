#include "primitives.h"

#include <algorithm>
#include <cmath>

namespace {

struct D3 {
  double x, y, z;
};
D3 d3(const Vec3& v) { return {v.x, v.y, v.z}; }
D3 sub(const D3& a, const D3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 cross(const D3& a, const D3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(const D3& a, const D3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// t is rounded to float before the interval test, so the interval holds for the t that is reported.
bool in_bounds(const Ray& ray, float t) { return t >= ray.dist_bounds[0] && t <= ray.dist_bounds[1]; }

}  // namespace

BBox Triangle::bbox() const {
  BBox b;
  b.enclose(p0);
  b.enclose(p1);
  b.enclose(p2);
  return b;
}

Trace Triangle::hit(const Ray& ray) const {
  Trace trace;
  const D3 o = d3(ray.point), d = d3(ray.dir), a = d3(p0);
  const D3 e1 = sub(d3(p1), a), e2 = sub(d3(p2), a);
  const D3 p = cross(d, e2);
  const double det = dot(e1, p);
  if (det == 0.0) return trace;  // the ray is parallel to the triangle's plane
  const D3 s = sub(o, a);
  const double u = dot(s, p) / det;
  if (u < 0.0 || u > 1.0) return trace;
  const D3 q = cross(s, e1);
  const double v = dot(d, q) / det;
  if (v < 0.0 || u + v > 1.0) return trace;
  const float t = static_cast<float>(dot(e2, q) / det);
  if (!in_bounds(ray, t)) return trace;
  trace.hit = true;
  trace.distance = t;
  trace.u = static_cast<float>(u);
  trace.v = static_cast<float>(v);
  trace.normal = normalize(cross(p1 - p0, p2 - p0));
  trace.geom_id = geom_id;
  trace.prim_id = prim_id;
  return trace;
}

BBox Sphere::bbox() const {
  BBox b;
  b.enclose(center - Vec3(radius, radius, radius));
  b.enclose(center + Vec3(radius, radius, radius));
  return b;
}

Trace Sphere::hit(const Ray& ray) const {
  Trace trace;
  // |o + t d - c| = r. The discriminant is taken from the vector of closest approach and the near root
  // through Vieta's formula, so neither far nor huge spheres lose their digits to cancellation.
  const D3 f = sub(d3(ray.point), d3(center)), d = d3(ray.dir);
  const double r = radius, a = dot(d, d), b = dot(f, d);
  const D3 l = {f.x - b / a * d.x, f.y - b / a * d.y, f.z - b / a * d.z};
  const double disc = a * (r * r - dot(l, l));
  if (!(disc >= 0.0)) return trace;
  const double flen = std::sqrt(dot(f, f));
  const double q = -(b + std::copysign(std::sqrt(disc), b));
  const double r0 = q == 0.0 ? 0.0 : (flen - r) * (flen + r) / q, r1 = q == 0.0 ? 0.0 : q / a;
  for (const double root : {std::min(r0, r1), std::max(r0, r1)}) {
    const float t = static_cast<float>(root);
    if (!in_bounds(ray, t)) continue;
    trace.hit = true;
    trace.distance = t;
    const Vec3 unit = normalize(ray.at(t) - center);
    trace.normal = unit;
    const double two_pi = 6.283185307179586;
    double phi = std::atan2(unit.z, unit.x);
    if (phi < 0.0) phi += two_pi;
    trace.u = std::min(static_cast<float>(phi / two_pi), 0.99999994f);
    trace.v = static_cast<float>(std::acos(std::clamp(static_cast<double>(unit.y), -1.0, 1.0)) / (two_pi / 2.0));
    trace.geom_id = geom_id;
    trace.prim_id = 0;
    return trace;
  }
  return trace;
}
