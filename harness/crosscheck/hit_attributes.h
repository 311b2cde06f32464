#pragma once
// Whether a hit's attributes (u, v and the geometric normal ng) follow the conventions of core/geometry/hit.h
// for the primitive it names. t and the primitive say *what* is hit and are ruled elsewhere (hit_comparison.h,
// the arbiter); u, v and ng say *where* and *which way it faces*, and a renderer uses them as they are: the
// hit point is (1-u-v) p0 + u p1 + v p2 (core/render/light_transport.h) and emission and spawned rays depend on
// the side ng names. Swapped barycentrics or a normal flipped toward the ray pass every t comparison and
// still render wrong, so they are judged on their own.
//
// What is right (tolerances, and why):
//  - every attribute is finite;
//  - triangles: ng is within an angle-like distance |ng - n| <= max(kNormalTolerance, kWorld * K) of
//    n = normalize(cross(p1 - p0, p2 - p0)), and the point (1-u-v) p0 + u p1 + v p2 lies within
//    kWorld * S * K / |cos| of the ray's line crossing of the triangle's plane. S is the largest absolute
//    coordinate of the vertices and the ray origin (the arbiter's local scale, harness/arbiter/tolerances.h),
//    K = Lmax^2 / (2 A) >= 1.15 the triangle's conditioning (longest edge squared over twice the area) and
//    cos the cosine between the ray and the plane's normal. Why: a float intersector's u, v (Moller-Trumbore or
//    the watertight test) are exact for vertices and ray moved by some ulps of S; such a move shifts the
//    barycentric point by that much times K, and the crossing by that much over |cos| (grazing rays make the
//    crossing ill-conditioned, and are excused in proportion). kWorld is 170 ulps of S, far above what a
//    correct test errs by and, for the scenes of the suites, far below the size of the triangles, so swapped
//    u and v, u and v of another vertex order, or barycentrics of the wrong triangle are caught;
//  - spheres: ng is within max(kNormalTolerance, kWorld * (|o| + |t d| + |c|) / r) of the outward normal at
//    the hit's own t, normalize(o + t d - c) (t itself is ruled elsewhere; at the silhouette it may be
//    anywhere on a short chord, and ng must face the way of the point it names), u and v lie in [0, 1] and
//    name the same direction: (sin(pi v) cos(2 pi u), cos(pi v), sin(pi v) sin(2 pi u)), within the same
//    tolerance (at the poles u is irrelevant and not judged, since sin(pi v) is 0).
// kNormalTolerance = 1e-3 (0.06 degrees) is far above the few ulps of a float normalize(cross(...)) of a
// well-shaped triangle and far below the error of a flipped (2), unnormalised or zero normal.

#include "core/geometry/hit.h"
#include "core/geometry/ray.h"
#include "harness/crosscheck/hit_comparison.h"

#include <string>

namespace twinray::crosscheck {

inline constexpr double kNormalTolerance = 1e-3;

struct AttributeRuling {
  bool right = true;
  std::string detail;  // why not, in one line (empty when right)
};

// The hit must name a primitive of `index` (a miss, or an unknown primitive, is right: there is nothing to
// judge, and unknown primitives are a contract violation caught before).
AttributeRuling rule_attributes(const GeometryIndex& index, const Ray& ray, const Hit& hit);

}  // namespace twinray::crosscheck
