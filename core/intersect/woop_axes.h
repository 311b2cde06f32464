#pragma once
// The axis permutation of Woop's watertight ray-triangle test (triangle_watertight.h), shared by the float
// test and its exact twin (core/exact/exact_triangle.cpp) so that both shear in the same frame.
//
// kz is the axis of the largest |dir| component (ties to the lower axis); kx, ky follow cyclically and are
// swapped when dir[kz] < 0: looking down a negative axis mirrors the 2D frame, and the swap restores the
// handedness, so the determinant keeps one sign convention for every ray.

#include <glm/gtc/type_ptr.hpp>

namespace twinray {

struct WoopAxes {
  int kx = 0, ky = 1, kz = 2;
};

// Vec is glm::vec3 or glm::dvec3 (a float converted to double compares the same way). Written without a
// branch on the axis: every query of every backend runs it once (glm's operator[] would be a switch).
template <class Vec>
[[gnu::always_inline]] inline WoopAxes woop_axes(const Vec& dir) {
  const auto ax = dir.x < 0 ? -dir.x : dir.x;
  const auto ay = dir.y < 0 ? -dir.y : dir.y;
  const auto az = dir.z < 0 ? -dir.z : dir.z;
  const int kz = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
  const int a = kz == 2 ? 0 : kz + 1;  // the axes after kz, cyclically
  const int b = a == 2 ? 0 : a + 1;
  const bool negative = glm::value_ptr(dir)[kz] < 0;
  WoopAxes w;
  w.kz = kz;
  w.kx = negative ? b : a;
  w.ky = negative ? a : b;
  return w;
}

}  // namespace twinray
