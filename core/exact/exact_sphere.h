#pragma once
// Ray-sphere intersection in exact arithmetic, with the conventions of core/intersect/sphere_robust.h.
//
// With f = org - center, the crossings of |org + t dir - center| = radius are the roots of
//     A t^2 + 2 B t + C = 0,   A = d.d > 0,  B = f.d,  C = f.f - r^2,   D = B^2 - A C,
// all integers at one power-of-two scale (GMP). D < 0: the line misses. D = 0: the line is tangent and
// counts once, at the rational root -B/A (the convention of sphere_robust.h). D > 0: two roots
// (-B -+ sqrt(D)) / A, rational when D is a perfect square (then rounded exactly like a quotient of
// integers), irrational otherwise.
//
// An irrational root is rounded by Ziv's strategy: it is evaluated in MPFR at precision P without
// cancellation (q = -(B + sign(B) sqrt(D)), roots q/A and C/q, as in sphere_robust.h), where each of the at
// most five correctly rounded operations adds a relative error of at most 2^-P, so the computed value x
// satisfies |x - root| < 2^(3-P) |x|; mpfr_can_round(x, P - 3, RNDN, RNDZ, p + 1) then proves that every
// value within that error rounds to the same float at the float precision p available at x's exponent
// (the documented MPFR idiom for round-to-nearest of a value known not to be representable), and
// otherwise P doubles. The root cannot be a float or a midpoint between two floats (those are rational),
// so the loop ends; a Liouville-type bound makes that quantitative: with D an integer that is not a
// square, |sqrt(D) - m/2^k| >= 1 / (2^(2k) (sqrt(D) + m/2^k)) for every dyadic m/2^k, so a precision of a
// few times the inputs' bit length (a few thousand bits) always decides; the loop allows 2^16 bits.
// The reported t is therefore the correctly rounded root (error at most half an ulp, within the one ulp
// asked of it), with IEEE gradual underflow and overflow to infinity.

#include <glm/vec3.hpp>

namespace twinray::exact {

struct RaySphere {
  glm::dvec3 org, dir, center;
  double radius = 0.0;
};

struct SphereCrossing {
  bool real = false;     // the line meets the sphere (D >= 0)
  bool tangent = false;  // D == 0: one crossing, t_near == t_far
  float t_near = 0.0f, t_far = 0.0f;            // correctly rounded roots, t_near <= t_far
  double near_double = 0.0, far_double = 0.0;   // the roots to double precision, for error figures
};

SphereCrossing intersect_sphere_exact(const RaySphere& in);

// The attributes of sphere_robust.h's sphere_hit_attributes at the near or far root, from the exact root:
// the outward unit normal (f + t d) / r, u = phi / 2 pi in [0, 1) with phi = atan2(n.z, n.x) in [0, 2 pi),
// v = acos(n.y) / pi. Evaluated in MPFR with at least 200 bits beyond any cancellation and rounded once, so
// each is within one ulp of its exact value. Requires `real`.
void sphere_attributes_exact(const RaySphere& in, bool use_far_root, glm::vec3& ng, float& u, float& v);

}  // namespace twinray::exact
