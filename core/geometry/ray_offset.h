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

}  // namespace twinray
