#pragma once
// Small pieces the deterministic ray sets share (crosscheck's kinds, axis_rays.h, the grader's sets in
// harness/grade/grade_rays.cpp): every draw comes from the caller's Rng, so a set stays a pure function of its
// seed.

#include "core/geometry/bounds.h"
#include "core/sampling/rng.h"
#include "core/scene/scene.h"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace twinray::crosscheck {

inline glm::vec2 next2(Rng& rng) { return {rng.next_float(), rng.next_float()}; }

// +0 or -0 with equal odds: direction components a slab test must treat by their sign.
inline float signed_zero(Rng& rng) { return (rng.next_u32() & 1u) != 0 ? -0.0f : 0.0f; }

// The scene's bounds, or a unit box around the origin for an empty scene.
inline Bounds3 scene_box_or_unit(const Scene& scene) {
  Bounds3 b = scene.geometry.bounds();
  if (b.empty()) b = {glm::vec3(-1.0f), glm::vec3(1.0f)};
  return b;
}

// The box grown by `fraction` of its diagonal on every side, and by at least a thousandth of its distance
// from the origin (at least 1e-3), so that origins drawn from it also lie clearly outside the scene. (The
// grader's sets were fixed with this rule; crosscheck's own kinds pad relative to the scene alone.)
inline Bounds3 padded_box(Bounds3 b, float fraction) {
  float distance = glm::length(b.center());
  // The float length overflows beyond about 1e19 (and an infinite pad makes every origin infinite); only then
  // is it taken in double, so that the rays of every other scene stay what they were.
  if (!std::isfinite(distance)) distance = static_cast<float>(std::min(
      glm::length(glm::dvec3(b.center())), static_cast<double>(std::numeric_limits<float>::max())));
  const float pad = std::max(fraction * b.diagonal(), 1e-3f * std::max(1.0f, distance));
  b.lo -= glm::vec3(pad);
  b.hi += glm::vec3(pad);
  return b;
}

inline glm::vec3 point_in(const Bounds3& b, Rng& rng) {
  const glm::vec3 u{rng.next_float(), rng.next_float(), rng.next_float()};
  return b.lo + u * (b.hi - b.lo);
}

}  // namespace twinray::crosscheck
