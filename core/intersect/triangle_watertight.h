#pragma once
// Watertight ray-triangle intersection.
//
// Method: Woop, Benthin, Wald, "Watertight Ray/Triangle Intersection", JCGT 2(1), 2013.
// The ray is made the +z axis of a sheared frame (a permutation, so that the largest direction component
// becomes z, then a shear that maps the direction to (0,0,1)). Triangle vertices are transformed into that
// frame and the hit test becomes a 2D point-in-triangle test of the origin with the three edge functions
//     U = cross2(C, B),  V = cross2(A, C),  W = cross2(B, A)     (A, B, C = sheared p0, p1, p2)
// Why it is watertight: a vertex's sheared coordinates depend only on the vertex and the ray, so two triangles
// sharing an edge evaluate that edge's function from bit-identical numbers, in opposite order: the two
// float results are exact negations. And fl(x*y) - fl(z*w) has the sign of x*y - z*w or is zero, because
// rounding is monotonic. So a non-zero float edge function always has the exact sign, and only an exact 0
// is ambiguous: then all three are recomputed in double, where products of floats are exact and the sign
// of the difference is exact too. (Far out in float's range a product can overflow: an infinite edge
// function still has the exact sign, and inf - inf = NaN takes the same double path, where the products are
// in range. The decision is exact while the sheared coordinates are finite: vertices within about 2^125 of
// the ray origin; stress case extreme-scale.)
//
// Edge ownership (never counted twice): the paper accepts a 0 edge function for both triangles of an edge.
// We add a fill rule so that a ray exactly through a shared edge or vertex hits exactly one triangle of a
// consistently oriented mesh: an edge whose function is exactly 0 only includes the origin when its
// direction, oriented so that the triangle lies on its right, satisfies  d.y > 0 || (d.y == 0 && d.x > 0).
// That is the same as moving the origin by an infinitesimal (eps, -eps^2) in the sheared plane before
// testing: a single perturbed point lies in exactly one triangle of a fan or of an edge pair, so ownership
// is unique, and it is decided from the same bit-identical vertex coordinates on both sides. (At a
// silhouette edge, where both triangles project to the same side, both or neither are hit, which keeps
// the inside/outside parity of a closed mesh.)
//
// Reported numbers: the edge test decides the hit; t, u, v are then computed by triangle_refine.h from the
// plane formulas with a rigorous error bound (exact GMP arithmetic when the bound cannot decide): t is the
// exact crossing parameter correctly rounded to float, u and v the exact barycentrics clamped to [0, 1] and
// correctly rounded. (Woop's own t, the weighted sum of sheared z over the determinant, loses the digits a
// grazing ray on a thin triangle needs: 6% on a Sponza moulding, issue 11.)
//
// Conventions:
//  - No backface culling; the winding only decides the sign of the determinant.
//  - A hit counts when tmin <= t <= tmax (closed, core/geometry/ray.h), with t the reported (correctly
//    rounded) float.
//  - Determinant exactly 0 (ray parallel to the triangle's plane, ray lying in the plane, or a triangle
//    whose projection is a segment) is a miss: there is no single crossing point to report.
//  - +0 and -0 direction components: the largest |dir| component is the divisor, and it is non-zero for
//    every valid ray, so the shear constants are finite; signed zeros only flow into products.
//  - Barycentrics: u = weight of p1, v = weight of p2 (core/geometry/hit.h).

#include "core/intersect/triangle_refine.h"
#include "core/intersect/woop_axes.h"

#include <glm/geometric.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/vec3.hpp>

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace twinray {

// Everything about the ray the triangle test needs, computed once per ray.
struct TriangleRay {
  // The permutation: kz = axis of the largest |dir| component (woop_axes.h). Pointer-sized, so that indexing
  // with them needs no sign extension (once per triangle block in the bvh kernels).
  std::ptrdiff_t kx = 0, ky = 1, kz = 2;
  float ox = 0.0f, oy = 0.0f, oz = 0.0f;  // origin, permuted: (org[kx], org[ky], org[kz])
  float sx = 0.0f, sy = 0.0f;  // shear: (dir[kx], dir[ky]) -> 0 (t comes from triangle_refine.h, so no z scale)
  refine_detail::RefineRay refine;  // the ray itself in double, for the t, u, v of triangle_refine.h
};

// The permutation, shear and permuted origin only: `refine` is left for the caller to fill with the ray in
// double (set_ray, or a kernel's vector conversion of the same floats, which gives the same doubles).
inline TriangleRay make_triangle_ray_frame(const glm::vec3& org, const glm::vec3& dir) {
  TriangleRay r;
  const WoopAxes axes = woop_axes(dir);
  r.kx = axes.kx;
  r.ky = axes.ky;
  r.kz = axes.kz;
  // value_ptr views a vector as float[3], so a permuted component is one indexed load; glm's operator[] is a
  // chain of compares per access.
  const float* d = glm::value_ptr(dir);
  const float* o = glm::value_ptr(org);
  r.sx = d[r.kx] / d[r.kz];
  r.sy = d[r.ky] / d[r.kz];
  r.ox = o[r.kx];
  r.oy = o[r.ky];
  r.oz = o[r.kz];
  return r;
}
inline TriangleRay make_triangle_ray(const glm::vec3& org, const glm::vec3& dir) {
  TriangleRay r = make_triangle_ray_frame(org, dir);
  refine_detail::set_ray(r.refine, org, dir);
  return r;
}

// The refinement of a triangle the edge test accepted (triangle_refine.h), for float vertices: the correctly
// rounded t when it lies in [tmin, tmax]; only whether it does (any-hit queries); the barycentrics of that
// crossing. Always inlined into the leaf tests, so that the vector code is compiled for the kernel's
// instruction set.
[[gnu::always_inline]] inline bool refine_triangle_t(const TriangleRay& ray, const glm::vec3& p0, const glm::vec3& p1,
                                                     const glm::vec3& p2, float tmin, float tmax, float& t) {
  return refine_detail::refine_t(ray.refine, p0, p1, p2, tmin, tmax, t);
}
[[gnu::always_inline]] inline bool refine_triangle_in_interval(const TriangleRay& ray, const glm::vec3& p0,
                                                               const glm::vec3& p1, const glm::vec3& p2, float tmin,
                                                               float tmax) {
  return refine_detail::refine_in_interval</*kDivisionFreeFirst=*/true>(ray.refine, p0, p1, p2, tmin, tmax);
}
// The barycentrics and the geometric normal (triangle_geometric_normal's bits) at once, from one e1 x e2:
// what a closest-hit traversal asks for its winner.
[[gnu::always_inline]] inline void triangle_hit_attributes(const TriangleRay& ray, const glm::vec3& p0,
                                                           const glm::vec3& p1, const glm::vec3& p2, float t,
                                                           float& u, float& v, glm::vec3& ng) {
  refine_detail::refine_uv(ray.refine, p0, p1, p2, t, u, v, &ng);
}
[[gnu::always_inline]] inline void triangle_barycentrics(const TriangleRay& ray, const glm::vec3& p0,
                                                         const glm::vec3& p1, const glm::vec3& p2, float t, float& u,
                                                         float& v) {
  refine_detail::refine_uv(ray.refine, p0, p1, p2, t, u, v);
}

namespace triangle_detail {

// Returns x after forcing it to be rounded to float in a register. GCC contracts a*b - c*d into an FMA
// by default under -march=native (even in ISO mode), and a fused product is not rounded: fma(a, b, -fl(c*d))
// and fma(c, d, -fl(a*b)) are no longer exact negations and can disagree in sign, which would reopen
// the cracks this algorithm closes. Every product below goes through it, so the result is the same
// IEEE float computation wherever the function is inlined: the sheared coordinates of a shared vertex are
// identical for all its triangles, and the bvh and brute backends report bit-identical t, u, v.
// The empty asm costs no instruction; it only hides the value from the optimizer.
inline float rounded(float x) {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
  asm("" : "+x"(x));
#elif defined(__GNUC__) && defined(__aarch64__)
  asm("" : "+w"(x));
#endif
  return x;
}

// Whether a zero edge function still includes the origin (fill rule above). (ex, ey) is the edge as stored,
// `positive` tells whether the triangle lies on its right (determinant > 0) or its left.
inline bool owns_edge(float ex, float ey, bool positive) {
  if (!positive) {
    ex = -ex;
    ey = -ey;
  }
  return ey > 0.0f || (ey == 0.0f && ex > 0.0f);
}

// Whether the float edge functions cannot decide the hit and the exact double path must: one of them is
// exactly 0 (a ray through an edge or a vertex: the fill rule decides), or NaN. A NaN comes from products
// that overflowed to infinities of one sign (inf - inf): sheared coordinates beyond about 1.3e19 (2^63), a scene
// or ray origin far out in float's range. An infinite edge function still has the exact sign (rounding is
// monotonic up to overflow), so it needs no detour. Mixed non-zero signs are rejected before this is asked.
inline bool needs_double(float u, float v, float w) {
  return u == 0.0f || v == 0.0f || w == 0.0f || std::isnan(u) || std::isnan(v) || std::isnan(w);
}

// What a triangle test reports for a hit: t, u and v; t only; only that there is one (any-hit queries: the
// correctly rounded t need not be known when its interval lies inside [tmin, tmax]).
enum class Report { kHit, kT, kAny };

// The watertight edge test, then the refinement, reporting as above.
template <Report kReport>
inline bool intersect(const TriangleRay& ray, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2, float tmin,
                      float tmax, float& t_out, float& u_out, float& v_out) {
  using triangle_detail::rounded;
  // Vertices relative to the origin, permuted. value_ptr views a vertex as float[3] (GLM guarantees the
  // layout), so a component is one indexed load; glm's operator[] would be a switch per access.
  const float* q0 = glm::value_ptr(p0);
  const float* q1 = glm::value_ptr(p1);
  const float* q2 = glm::value_ptr(p2);
  const float a_z = q0[ray.kz] - ray.oz;
  const float b_z = q1[ray.kz] - ray.oz;
  const float c_z = q2[ray.kz] - ray.oz;
  const float ax = (q0[ray.kx] - ray.ox) - rounded(ray.sx * a_z);
  const float ay = (q0[ray.ky] - ray.oy) - rounded(ray.sy * a_z);
  const float bx = (q1[ray.kx] - ray.ox) - rounded(ray.sx * b_z);
  const float by = (q1[ray.ky] - ray.oy) - rounded(ray.sy * b_z);
  const float cx = (q2[ray.kx] - ray.ox) - rounded(ray.sx * c_z);
  const float cy = (q2[ray.ky] - ray.oy) - rounded(ray.sy * c_z);

  float u = rounded(cx * by) - rounded(cy * bx);
  float v = rounded(ax * cy) - rounded(ay * cx);
  float w = rounded(bx * ay) - rounded(by * ax);
  // Mixed signs first: it rejects almost every triangle a ray is tested against, and it is right even when
  // another edge function is exactly 0, since a non-zero one has the exact sign (above): the double path
  // below would reject the same triangle.
  if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return false;
  if (needs_double(u, v, w)) {
    // Exact in double: each product of two floats fits in 48 bits and in double's range, and the difference
    // is rounded once, which preserves its sign (and contraction into an FMA cannot change an exact product).
    const double du = double(cx) * double(by) - double(cy) * double(bx);
    const double dv = double(ax) * double(cy) - double(ay) * double(cx);
    const double dw = double(bx) * double(ay) - double(by) * double(ax);
    if ((du < 0.0 || dv < 0.0 || dw < 0.0) && (du > 0.0 || dv > 0.0 || dw > 0.0)) return false;
    // The determinant in double too: edge functions of a triangle at 1e-30 are about 1e-60, which a float
    // copy would flush to 0, and their sum (all of one sign) is 0 only when all three are.
    const double det = du + dv + dw;
    if (det == 0.0) return false;  // parallel, in-plane or projected to a segment: see conventions above
    const bool positive = det > 0.0;
    if (du == 0.0 && !triangle_detail::owns_edge(cx - bx, cy - by, positive)) return false;
    if (dv == 0.0 && !triangle_detail::owns_edge(ax - cx, ay - cy, positive)) return false;
    if (dw == 0.0 && !triangle_detail::owns_edge(bx - ax, by - ay, positive)) return false;
    if (std::isnan(det)) return false;  // sheared coordinates overflowed too (coordinates beyond 2^125): undecidable
  }
  // Otherwise the three are non-zero, not NaN and of one sign, so their sum (the determinant) is not 0.
  if constexpr (kReport == Report::kAny) {
    return refine_triangle_in_interval(ray, p0, p1, p2, tmin, tmax);
  } else {
    if (!refine_triangle_t(ray, p0, p1, p2, tmin, tmax, t_out)) return false;
    if constexpr (kReport == Report::kHit) triangle_barycentrics(ray, p0, p1, p2, t_out, u_out, v_out);
    return true;
  }
}

}  // namespace triangle_detail

// Intersects the ray with triangle (p0, p1, p2). On a hit with tmin <= t <= tmax, writes t and the
// barycentrics (u for p1, v for p2), correctly rounded, and returns true.
inline bool intersect_triangle(const TriangleRay& ray, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2,
                               float tmin, float tmax, float& t_out, float& u_out, float& v_out) {
  return triangle_detail::intersect<triangle_detail::Report::kHit>(ray, p0, p1, p2, tmin, tmax, t_out, u_out, v_out);
}

// The same hit decision and t, without the barycentrics: a closest-hit traversal asks
// triangle_barycentrics for the winner's u and v once, at the end.
inline bool intersect_triangle_t(const TriangleRay& ray, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2,
                                 float tmin, float tmax, float& t_out) {
  float unused_u, unused_v;
  return triangle_detail::intersect<triangle_detail::Report::kT>(ray, p0, p1, p2, tmin, tmax, t_out, unused_u,
                                                                 unused_v);
}

// Only whether the ray hits the triangle within [tmin, tmax] (any-hit queries).
inline bool intersect_triangle_any(const TriangleRay& ray, const glm::vec3& p0, const glm::vec3& p1,
                                   const glm::vec3& p2, float tmin, float tmax) {
  float unused_t, unused_u, unused_v;
  return triangle_detail::intersect<triangle_detail::Report::kAny>(ray, p0, p1, p2, tmin, tmax, unused_t, unused_u,
                                                                   unused_v);
}

// normalize(cross(p1 - p0, p2 - p0)), evaluated in double so that tiny (but hit) triangles, whose float
// cross product would underflow, still get a unit normal. A triangle whose vertices are exactly collinear
// cannot be hit (its determinant is 0), so the fallback (0, 0, 1) only guards against misuse. The same bits
// as the normal a closest-hit traversal takes from the winner's kept crossing (triangle_refine.h).
inline glm::vec3 triangle_geometric_normal(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2) {
  return refine_detail::geometric_normal(p0, p1, p2);
}

}  // namespace twinray
