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
//    1e-4 relative. This is the crosscheck's t tolerance with the scene diagonal replaced by S. It does not
//    grow at grazing angles: a triangle's crossing is a well-conditioned quotient that a careful
//    implementation computes to a few ulps (Embree's robust kernels do; Woop's weighted sum of sheared z,
//    the old bvh t, was 6% off on a 500:1 Sponza moulding at cos -0.0034, issue 11).

namespace twinray::arbiter {

inline constexpr double kWorld = 1e-5;
inline constexpr double kRelT = 1e-4;

}  // namespace twinray::arbiter
