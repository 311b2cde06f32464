#include "core/exact/exact_triangle.h"

#include "core/exact/exact_integer.h"
#include "core/intersect/woop_axes.h"

namespace twinray::exact {

namespace {

// The inputs as integers at one scale (the common factor 2^scale cancels in every sign and quotient below).
struct IntegerRayTriangle {
  IVec3 o, d, p0, p1, p2;
};

IntegerRayTriangle to_integers(const RayTriangle& in) {
  const ScaledIntegers s{in.org.x, in.org.y, in.org.z, in.dir.x, in.dir.y, in.dir.z, in.p0.x, in.p0.y, in.p0.z,
                         in.p1.x,  in.p1.y,  in.p1.z,  in.p2.x,  in.p2.y,  in.p2.z};
  const auto vec = [&s](std::size_t i) { return IVec3{s.at(i), s.at(i + 1), s.at(i + 2)}; };
  return {vec(0), vec(3), vec(6), vec(9), vec(12)};
}

// x / den clamped to [0, 1], rounded to float.
float clamped_barycentric(const mpz_class& x, const mpz_class& den) {
  if (sgn(x) == 0 || sgn(x) != sgn(den)) return 0.0f;
  if (cmp(abs(x), abs(den)) >= 0) return 1.0f;
  return round_quotient_to_float(x, den);
}

// Whether an edge whose edge function is exactly 0 includes the origin (triangle_watertight.h's fill rule):
// its direction, oriented so that the triangle lies on its right, must satisfy y > 0 || (y == 0 && x > 0).
// `edge` is the edge's 3D direction; its sheared 2D direction, scaled by |d_kz| > 0 (which changes no
// sign), is (edge_kx |d_kz| - d_kx sgn(d_kz) edge_kz, edge_ky |d_kz| - d_ky sgn(d_kz) edge_kz).
bool owns_edge(const IVec3& edge, const IVec3& d, const WoopAxes& axes, bool positive) {
  const mpz_class& dz = d[axes.kz];
  const mpz_class abs_dz = abs(dz);
  mpz_class ex = edge[axes.kx] * abs_dz, ey = edge[axes.ky] * abs_dz;
  if (sgn(dz) > 0) {
    ex -= d[axes.kx] * edge[axes.kz];
    ey -= d[axes.ky] * edge[axes.kz];
  } else {
    ex += d[axes.kx] * edge[axes.kz];
    ey += d[axes.ky] * edge[axes.kz];
  }
  if (!positive) {
    ex = -ex;
    ey = -ey;
  }
  return sgn(ey) > 0 || (sgn(ey) == 0 && sgn(ex) > 0);
}

}  // namespace

TriangleCrossing intersect_triangle_exact(const RayTriangle& in) {
  const IntegerRayTriangle r = to_integers(in);
  const IVec3 a = r.p0 - r.o, b = r.p1 - r.o, c = r.p2 - r.o;
  const IVec3 bc = cross(b, c);
  const mpz_class e[3] = {dot(r.d, bc), dot(r.d, cross(c, a)), dot(r.d, cross(a, b))};
  const mpz_class den = e[0] + e[1] + e[2];

  TriangleCrossing out;
  for (int i = 0; i < 3; ++i) out.sign[i] = sgn(e[i]);
  out.parallel = sgn(den) == 0;
  if (!out.parallel) {
    const mpz_class num = dot(a, bc);
    out.t = round_quotient_to_float(num, den);
    out.t_double = quotient_to_double(num, den);
    out.u = clamped_barycentric(e[1], den);
    out.v = clamped_barycentric(e[2], den);
  }

  const bool any_negative = out.sign[0] < 0 || out.sign[1] < 0 || out.sign[2] < 0;
  const bool any_positive = out.sign[0] > 0 || out.sign[1] > 0 || out.sign[2] > 0;
  if (out.parallel || (any_negative && any_positive)) return out;
  // Woop's determinant is -den / |d_kz|: positive means den < 0.
  const bool positive = sgn(den) < 0;
  const WoopAxes axes = woop_axes(in.dir);
  // Edge functions U, V, W belong to the edges b -> c, c -> a, a -> b (opposite p0, p1, p2).
  const IVec3* from[3] = {&b, &c, &a};
  const IVec3* to[3] = {&c, &a, &b};
  for (int i = 0; i < 3; ++i)
    if (out.sign[i] == 0 && !owns_edge(*to[i] - *from[i], r.d, axes, positive)) return out;
  out.hit = true;
  return out;
}

bool triangle_crossing_attributes(const RayTriangle& in, float& t, float& u, float& v) {
  const IntegerRayTriangle r = to_integers(in);
  const IVec3 a = r.p0 - r.o, e1 = r.p1 - r.p0, e2 = r.p2 - r.p0;
  const IVec3 n = cross(e1, e2);
  const mpz_class den = dot(r.d, n);
  if (sgn(den) == 0) return false;
  // e1 . (d x a)-style numerators, as in the double path: u = (p2 - p0) . (a x d) / den, v = -(p1 - p0) . (a x d) / den.
  const IVec3 q = cross(a, r.d);
  t = round_quotient_to_float(dot(a, n), den);
  u = clamped_barycentric(dot(e2, q), den);
  v = clamped_barycentric(-dot(e1, q), den);
  return true;
}

}  // namespace twinray::exact
