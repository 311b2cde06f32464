#pragma once
// Ray-triangle intersection in exact arithmetic: the oracle behind the `exact` backend, the arbiter, and
// the fallback of the bvh's correctly rounded t (core/intersect/triangle_refine.h).
//
// The inputs are taken as the exact rationals they are (doubles that hold floats). With a = p0 - o,
// b = p1 - o, c = p2 - o and n = (p1 - p0) x (p2 - p0):
//   barycentric numerators   e0 = d.(b x c), e1 = d.(c x a), e2 = d.(a x b)     (weights of p0, p1, p2)
//   determinant              den = d.n = e0 + e1 + e2
//   crossing parameter       t = [a, b, c] / den = a.(b x c) / den
//   barycentrics             u = e1 / den (weight of p1), v = e2 / den (weight of p2)
// all as integers at one power-of-two scale (GMP), each quotient rounded once to float (MPFR).
//
// Hit decision: the one of core/intersect/triangle_watertight.h, evaluated without rounding. Woop's
// sheared edge functions are U = -e0/|d_kz|, V = -e1/|d_kz|, W = -e2/|d_kz| (a positive factor: the
// permutation's parity and the swap for a negative d_kz cancel), so the ray's line meets the closed
// triangle iff e0, e1, e2 have no two opposite signs; a zero edge function counts only when the fill rule
// gives the edge to this triangle, with the edge's direction taken in the *exact* sheared frame (Woop's
// determinant U + V + W > 0 iff den < 0 orients it). den = 0 is a miss (no single crossing point). So on
// a shared edge or vertex exactly one triangle of a consistently oriented mesh is hit, and the answer
// depends on nothing but the inputs.

#include <glm/vec3.hpp>

namespace twinray::exact {

// A ray's line and a triangle, every value exact (a float converted to double exactly, e.g. with
// to_double_exact, or a value the caller's arithmetic has already produced).
struct RayTriangle {
  glm::dvec3 org, dir, p0, p1, p2;
};

struct TriangleCrossing {
  bool hit = false;       // the fill-rule decision; false when parallel
  bool parallel = false;  // den == 0: the line is parallel to the plane, lies in it, or the triangle is degenerate
  int sign[3] = {0, 0, 0};  // signs of e0, e1, e2
  // When !parallel: t, u, v of the line's crossing with the plane, each correctly rounded to float (round to
  // nearest, ties to even, gradual underflow, +-inf on overflow); u and v clamped to [0, 1] first (they lie in
  // it whenever `hit`).
  float t = 0.0f, u = 0.0f, v = 0.0f;
  double t_double = 0.0;  // t rounded to double instead, for error figures
};

TriangleCrossing intersect_triangle_exact(const RayTriangle& in);

// Only the correctly rounded t, u, v (u, v clamped), for callers that decided the hit themselves. False
// when den == 0.
bool triangle_crossing_attributes(const RayTriangle& in, float& t, float& u, float& v);

}  // namespace twinray::exact
