#pragma once
// Spawning secondary rays without self-intersection.
//
// Wächter and Binder, "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing Gems ch. 6.
// The hit point is moved along the geometric normal by a few ulps of its own coordinates, in integer
// ulp space, so the offset scales with the magnitude of the position: no global epsilon, correct for the
// 0.1-unit bunny and the 35-unit Sponza alike. Near the origin, where ulps become tiny, a small fixed
// offset (kFloatScale) takes over.
//
// Constants (from the chapter, kept as published):
//  kOrigin     = 1/32: below this coordinate magnitude the fixed offset is used;
//  kFloatScale = 1/65536: the fixed offset, in world units, near the origin;
//  kIntScale   = 256: the offset in ulps elsewhere (covers the error of a float triangle hit point).

#include <glm/vec3.hpp>

#include <bit>
#include <cmath>
#include <cstdint>

namespace twinray {

inline glm::vec3 offset_ray_origin(const glm::vec3& p, const glm::vec3& n) {
  constexpr float kOrigin = 1.0f / 32.0f;
  constexpr float kFloatScale = 1.0f / 65536.0f;
  constexpr float kIntScale = 256.0f;
  glm::vec3 result;
  for (int k = 0; k < 3; ++k) {
    const auto of_i = static_cast<std::int32_t>(kIntScale * n[k]);
    const auto bits = std::bit_cast<std::int32_t>(p[k]);
    const float p_i = std::bit_cast<float>(bits + ((p[k] < 0.0f) ? -of_i : of_i));
    result[k] = std::fabs(p[k]) < kOrigin ? p[k] + kFloatScale * n[k] : p_i;
  }
  return result;
}

// The same for a point whose error is set by coordinates of magnitude `scale` larger than its own: the
// middle of a triangle whose vertices lie far away (a 2000-unit ground plane seen near the origin) has
// a reconstruction and intersection error of ulps of the *vertices*, not of the point. The result is the
// Wächter-Binder point, or the point moved kIntScale ulps of `scale` along n when that is farther.
inline glm::vec3 offset_ray_origin(const glm::vec3& p, const glm::vec3& n, float scale) {
  constexpr float kIntScale = 256.0f;           // as above
  constexpr float kUlpPerMagnitude = 0x1p-23f;  // one float ulp relative to the magnitude
  const glm::vec3 q = offset_ray_origin(p, n);
  const float min_offset = kIntScale * kUlpPerMagnitude * scale;
  const float offset = (q.x - p.x) * n.x + (q.y - p.y) * n.y + (q.z - p.z) * n.z;
  return offset >= min_offset ? q : p + min_offset * n;
}

}  // namespace twinray
