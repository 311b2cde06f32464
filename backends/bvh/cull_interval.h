#pragma once
// The interval a traversal tests boxes against: the ray's [tmin, tmax] widened by a relative 2^-21.
// Shared by every tree (bvh, bvh8) so all of them cull exactly alike.

namespace twinray {

// Boxes are tested against a slightly wider interval than the primitives. A primitive counts when its
// *correctly rounded* t lies in [tmin, tmax], so its exact t may lie half an ulp outside; and a box's computed
// entry can exceed the exact one by gamma(3) (ray_box.h: the far distance is scaled, the near one is not).
// Without the widening a box whose entry is the closest hit's own t, holding a second triangle crossed at
// the same rounded t (coplanar triangles of a floor, where the box is flat), is culled, and the tie goes to
// whichever triangle was found first instead of the lower id: found by the arbiter on Sponza (issue 11).
// 2^-21 covers gamma(3) (3 * 2^-24 over 1 - 3 * 2^-24) plus half an ulp (at most 2^-24 relative) with room
// for the rounding of the scaled bound itself. tmin, tmax >= 0, so scaling moves them outward; inf stays.
inline constexpr float kCullUp = 1.0f + 0x1p-21f, kCullDown = 1.0f - 0x1p-21f;
inline float cull_max(float tmax) { return tmax * kCullUp; }
inline float cull_min(float tmin) { return tmin * kCullDown; }

}  // namespace twinray
