#pragma once
// The axis permutation of Woop's watertight ray-triangle test (triangle_watertight.h), shared by the float
// test and its exact twin (core/exact/exact_triangle.cpp) so that both shear in the same frame.
//
// kz is the axis of the largest |dir| component (ties to the lower axis); kx, ky follow cyclically and are
// swapped when dir[kz] < 0: looking down a negative axis mirrors the 2D frame, and the swap restores the
// handedness, so the determinant keeps one sign convention for every ray.

#include <glm/gtc/type_ptr.hpp>

#include <cmath>

namespace twinray {

struct WoopAxes {
  int kx = 0, ky = 1, kz = 2;
};

// Vec is glm::vec3 or glm::dvec3 (a float converted to double compares the same way). Written without a
// branch: every query of every backend runs it once. The three comparisons index a table of kz (the same
// comparisons as "ax >= ay && ax >= az ? 0 : ay >= az ? 1 : 2", NaN included), and kz with the sign of
// dir[kz] one of kx, ky (glm's operator[] would be a switch).
template <class Vec>
[[gnu::always_inline]] inline WoopAxes woop_axes(const Vec& dir) {
  static constexpr int kLargest[8] = {2, 2, 2, 0, 1, 1, 1, 0};  // by (ax >= ay) | (ax >= az) << 1 | (ay >= az) << 2
  static constexpr int kAfter[3][2] = {{1, 2}, {2, 0}, {0, 1}};  // the two axes after kz, cyclically
  // |x| (one mask operation); -0 and +0 compare alike, so the table sees the same comparisons either way.
  const auto ax = std::fabs(dir.x), ay = std::fabs(dir.y), az = std::fabs(dir.z);
  const int kz = kLargest[int{ax >= ay} | int{ax >= az} << 1 | int{ay >= az} << 2];
  const int negative = int{glm::value_ptr(dir)[kz] < 0};
  WoopAxes w;
  w.kz = kz;
  w.kx = kAfter[kz][negative];
  w.ky = kAfter[kz][1 - negative];
  return w;
}

}  // namespace twinray
