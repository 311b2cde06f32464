#pragma once
// The axis permutation of Woop's watertight ray-triangle test (triangle_watertight.h), shared by the float
// test and its exact twin (core/exact/exact_triangle.cpp) so that both shear in the same frame.
//
// kz is the axis of the largest |dir| component (ties to the lower axis); kx, ky follow cyclically and are
// swapped when dir[kz] < 0: looking down a negative axis mirrors the 2D frame, and the swap restores the
// handedness, so the determinant keeps one sign convention for every ray.

namespace twinray {

struct WoopAxes {
  int kx = 0, ky = 1, kz = 2;
};

// Vec is glm::vec3 or glm::dvec3 (a float converted to double compares the same way).
template <class Vec>
[[gnu::always_inline]] inline WoopAxes woop_axes(const Vec& dir) {
  const auto ax = dir.x < 0 ? -dir.x : dir.x;
  const auto ay = dir.y < 0 ? -dir.y : dir.y;
  const auto az = dir.z < 0 ? -dir.z : dir.z;
  WoopAxes w;
  w.kz = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
  w.kx = w.kz == 2 ? 0 : w.kz + 1;
  w.ky = w.kx == 2 ? 0 : w.kx + 1;
  if (dir[w.kz] < 0) {
    const int tmp = w.kx;
    w.kx = w.ky;
    w.ky = tmp;
  }
  return w;
}

}  // namespace twinray
