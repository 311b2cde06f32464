#pragma once
// Rays whose interval ends exactly where they cross a triangle, for the ray-interval check (docs/grading.md,
// "Interval ends"). twinray_plugin.h promises a closed interval: a hit counts when tmin <= t <= tmax. The
// ray-interval check's other rays stop 1e-3 of t short of a surface or past it, and the arbiter forgives any
// decision within its t tolerance of tmin or tmax (harness/arbiter/arbiter.h, interval-end), because a float
// test's t is rounded; so neither can tell `tmin <= t <= tmax` from `tmin < t < tmax`. These rays can: they
// cross triangles where every float triangle test computes t exactly, so the answer at the ends is not a
// matter of rounding, and they are judged strictly.

#include "core/geometry/hit.h"
#include "core/geometry/ray.h"
#include "core/scene/scene.h"
#include "harness/arbiter/arbiter.h"
#include "harness/grade/answers.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace twinray::grade {

// A ray whose interval ends exactly at its crossing with a target triangle (t == tmin or t == tmax), or
// one float short of it.
struct IntervalEndRay {
  Ray ray;
  bool counts = false;                     // the crossing lies in [tmin, tmax] (at one of its ends)
  std::uint32_t geom_id = 0, prim_id = 0;  // the target triangle
  float t = 0.0f;                          // where the ray crosses it
};

// Up to `count` such rays, only at triangles where every float triangle test computes t exactly: triangles in
// a coordinate plane with integer vertices (|c| <= 1024) and twice their area a power of two (the unit
// squares of procedural:box and procedural:grid, the Cornell box's walls), crossed along that plane's axis at
// barycentrics (1/2, 1/4, 1/4), far from every edge, from an origin 1/2, 1 or 2 away. Four intervals:
// [0, d] and [d, 2d] (the crossing counts), [0, d-] and [d+, 2d] (one float short of it: it does not).
// None when the scene has no such triangle. A pure function of the scene and the seed.
std::vector<IntervalEndRay> interval_end_rays(const Scene& scene, std::size_t count, std::uint64_t seed);

// The rays whose exact answer (exact arithmetic on the float ray) is unambiguous: the target itself at
// exactly its t when the crossing counts, and nothing at all when it does not (so that any hit is wrong).
std::vector<IntervalEndRay> unambiguous_ends(const arbiter::Arbiter& exact, std::vector<IntervalEndRay> ends);

// The answers to such rays (closest hit and any hit, in the rays' order), judged against what they must be:
// the target hit (with t in [tmin, tmax]) and occluded when the crossing counts, a miss and not occluded when
// it does not.
struct EndJudgement {
  std::size_t wrong = 0;             // wrong answers, closest and any-hit
  std::optional<std::size_t> first;  // the first ray with a wrong answer
  bool first_any_hit = false;        // its any-hit answer is the wrong one (its closest hit is right)
  std::string first_description;     // one line
};
EndJudgement judge_ends(std::span<const IntervalEndRay> ends, const Answers& answers);

}  // namespace twinray::grade
