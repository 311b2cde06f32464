#pragma once
// The arbiter: rules one backend's answer to one ray right or wrong, against the `exact` backend
// (backends/exact/exact_backend.h), and says why. Used by `twinray crosscheck` on every disagreement and by
// anything else that grades intersectors.
//
// What "right" means. The exact answer (the closest hit under the contract of core/geometry/ray.h and hit.h,
// every decision exact, t correctly rounded) is always right. A float intersector works on rounded
// coordinates, so an answer that differs from the exact one is still right when a perturbation of the
// scene and ray within the world tolerance (harness/arbiter/tolerances.h: delta = 1e-5 of the local
// coordinate scale S) would make it the exact answer, *and* its t is within the t tolerance
// (1e-4 relative + 1e-5 S / |dir|) of the exact crossing of the primitive it names. Concretely:
//
//   closest hit, answer = primitive X at t:
//     - X must be reached: the ray's line passes within delta of X           (else wrong: hit-not-there)
//     - t must lie in [tmin, tmax]                                            (else wrong: outside-interval)
//     - t must be within the t tolerance of X's exact crossing (a sphere near
//       its silhouette: anywhere on the chord of the sphere grown by delta)   (else wrong: t-off)
//     - every exact hit clearly closer than X (by more than the t tolerance) must be *avoidable*
//                                                                             (else wrong: wrong-primitive)
//     - a backend that claims ties (honours_ties) must resolve an exact tie (the same correctly rounded t
//       on two primitives crossed away from their edges) to the lower (geom_id, prim_id)
//                                                                             (else wrong: tie-broken-wrongly)
//   closest hit, answer = miss: every exact hit must be avoidable            (else wrong: missed-hit)
//   any hit, answer = occluded: some primitive must be reached at a t within tolerance of [tmin, tmax]
//                                                                             (else wrong: hit-not-there)
//   any hit, answer = not occluded: every exact hit must be avoidable        (else wrong: missed-hit)
//   invalid rays (ray.h): only a miss is right                               (else wrong: hit-not-there)
//
// An exact hit is *avoidable* when its t is within the t tolerance of tmin or tmax (interval-end), or the
// line passes within delta of its boundary (edge): of a sphere's silhouette, or of a triangle edge, where
// for a backend that claims watertightness the edge must also be one the ray can leave the surface through
// (a mesh boundary, or a silhouette edge whose neighbour lies on the same side seen along the ray: see
// edge_map.h). A watertight backend may therefore hand an edge crossing to either neighbour, but not lose
// it. Everything else is wrong.
//
// A right answer that differs from the exact one is reported with the reason that made it right: edge,
// tie (equal t within tolerance, or a tie broken either way by a backend that does not claim ties) or
// interval-end. u, v and the normal are not judged here (the arbiter rules what is hit); the grader judges
// them separately, with tolerances that grow for slivers and grazing rays (harness/crosscheck/hit_attributes.h).
//
// Thread-safe: every member function is const and allocates its own exact numbers.

#include "core/backend/backend.h"
#include "core/geometry/hit.h"
#include "core/geometry/ray.h"
#include "core/geometry/scene_geometry.h"

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

namespace twinray::arbiter {

enum class Reason {
  // Right.
  Agrees,        // the exact answer (t within tolerance)
  Edge,          // differs at an edge, vertex or silhouette the ray passes within delta of
  Tie,           // a different primitive at the same t within tolerance
  IntervalEnd,   // an exact hit within tolerance of tmin or tmax, counted or not
  // Wrong.
  HitNotThere,       // a hit (or occlusion) where the ray reaches no primitive in the interval, or a primitive it does not reach
  MissedHit,         // a miss (or no occlusion) where the ray certainly crosses a primitive
  WrongPrimitive,    // a primitive behind one the ray certainly crosses first
  TOff,              // the right primitive, t outside the tolerance of its exact crossing
  TieBrokenWrongly,  // an exact tie resolved to the higher (geom_id, prim_id) by a backend that claims ties
  OutsideInterval,   // a reported t outside [tmin, tmax]
};
inline constexpr std::size_t kReasonCount = 10;
std::string_view to_string(Reason r);
bool is_wrong(Reason r);

struct Ruling {
  bool right = true;
  Reason reason = Reason::Agrees;
  Hit exact;                    // the exact closest hit (also filled by rule_occluded)
  bool exact_occluded = false;  // whether the exact ray hits anything in [tmin, tmax]
  // |t - t_exact| / |t_exact| between the answer's t and the exact crossing of the primitive the answer
  // names (the exact hit itself when they agree); negative when undefined (a miss, or no crossing).
  double t_rel_error = -1.0;
  std::string detail;  // one line: what the exact ray does, for wrong answers and differences
};

class Arbiter {
 public:
  // Builds the exact backend over `geometry`, which must outlive the arbiter.
  explicit Arbiter(const SceneGeometry& geometry);
  ~Arbiter();
  Arbiter(const Arbiter&) = delete;
  Arbiter& operator=(const Arbiter&) = delete;

  Ruling rule_closest(const Ray& ray, const Hit& answer, const BackendTraits& traits) const;
  Ruling rule_occluded(const Ray& ray, bool answer, const BackendTraits& traits) const;

  // The exact answers themselves.
  Hit exact_closest(const Ray& ray) const;
  bool exact_occluded(const Ray& ray) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace twinray::arbiter
