#pragma once
// The arbiter's two tolerances, and the scale they are relative to (docs/exact-backend.md, "The arbiter").
//
// A float intersector works on coordinates rounded to float: its decisions are those of a scene and a ray
// perturbed by some ulps of the coordinates it subtracts. The arbiter therefore measures every tolerance
// against the *local coordinate scale* of a primitive and a ray,
//     S = the largest absolute coordinate among the ray origin and the primitive's vertices
//         (a sphere: |center| + radius),
// never against the scene's size, so a small object in a large scene is judged at its own precision.
//
//  - kWorld: distances. A primitive is *reached* by the ray when the ray's line passes within
//    delta = kWorld * S of it, and a crossing is *on an edge* (or a sphere's silhouette) when the line passes
//    within delta of the boundary. 1e-5 is about 170 float ulps of S: far above the error of any float
//    test (a watertight test's sheared coordinates are within ~12 ulps of S), far below the size of
//    anything a traversal bug loses. The same constant as the crosscheck classifier's (hit_comparison.h).
//  - kRelT with kWorld: parameters. A reported t is *right* for a primitive when
//        |t - t_exact| <= kRelT |t_exact| + kWorld S / |dir|,
//    i.e. the reported hit point o + t d lies within kWorld * S of the exact one along the ray, or within
//    1e-4 relative. This is the crosscheck's t tolerance with the scene diagonal replaced by S. By itself it
//    does not grow at grazing angles (kGrazeT adds what a textbook test rounds there): a triangle's crossing
//    is a well-conditioned quotient that a careful implementation computes to a few ulps (Embree's robust kernels do; Woop's weighted sum of sheared z,
//    the old bvh t, was 6% off on a 500:1 Sponza moulding at cos -0.0034, issue 11).
//  - kGrazeT: a triangle's t at grazing angles. The crossing of a plane is ill-conditioned in the plane's
//    position: moving the plane by e (what rounding the coordinates a test subtracts does, ulps of S) moves
//    the crossing by e / |cos| along the ray. A textbook float Moller-Trumbore (t = [e2, o - p0, e1] / det,
//    no care taken) rounds its numerator and det each by a few u |e1| |e2| (|o - p0| + |t d|) with u = 2^-24:
//    about c u S K / (|cos| |dir|) in t for c up to about 30, K the longest edge squared over twice the area
//    (the attribute rule's, hit_attributes.h). Measured: 1.03e-5 S along the ray at cos 0.0025 on the Cornell
//    box (tests/plugins/lbvh_plugin.c; docs/grading.md "An independent plugin: the LBVH"), over kWorld S.
//    So a triangle's t tolerance is at least
//        kGrazeT S K / (|cos| |dir|),   kGrazeT = 32 u = 2^-19,
//    which exceeds kWorld S / |dir| only where K / |cos| > 5.2 (grazing rays, slivers): everywhere else the
//    rule is as before. It is still a tenth of the attribute rule's point tolerance, 1e-5 S K / |cos|.

namespace twinray::arbiter {

inline constexpr double kWorld = 1e-5;
inline constexpr double kRelT = 1e-4;
inline constexpr double kGrazeT = 0x1p-19;  // 1.9e-6

}  // namespace twinray::arbiter
