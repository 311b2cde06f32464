#pragma once
// The arbiter's part of a cross-check: every ray on which two backends disagree (closest hits not identical,
// or any-hit answers different) is ruled, for every backend, against the exact answer
// (harness/arbiter/arbiter.h), and the rulings are tallied per backend.
//
// Every backend is ruled on a disputed ray, not only the two that disagree: the exact answer is computed
// once per ray anyway, and a third backend that sides with a wrong one is then caught too. Rulings run in
// parallel (TBB); the tallies and the examples are in ray order, so the output does not depend on the thread
// count. At most `max_rays` rays are ruled per call (the first ones, in ray order): a very broken backend
// disagrees on every ray, and the exact answers cost tens of microseconds each.

#include "harness/arbiter/arbiter.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace twinray::crosscheck {

// One backend's answers to a ray set.
struct BackendAnswers {
  std::string name;
  BackendTraits traits;
  std::span<const Hit> closest;
  std::span<const std::uint8_t> occluded;
};

struct WrongAnswer {
  std::size_t ray_index = 0;
  Ray ray;
  bool occlusion = false;  // an any-hit answer rather than a closest hit
  Hit answer;
  bool answered_occluded = false;
  arbiter::Ruling ruling;
};

struct ArbiterTally {
  std::size_t ruled = 0;  // answers ruled: closest hits, and any-hit answers of rays whose any-hit answers differ
  std::size_t wrong = 0;
  double max_t_rel_error = 0.0;  // over ruled closest hits that name a primitive with an exact crossing
  std::array<std::size_t, arbiter::kReasonCount> reasons{};
  std::vector<WrongAnswer> examples;  // the first wrong answers, in ray order
};

struct ArbitrationResult {
  std::size_t disputed_rays = 0;
  std::size_t ruled_rays = 0;  // < disputed_rays when the cap was reached
  double seconds = 0.0;
  std::vector<ArbiterTally> backends;  // parallel to the answers
  bool capped() const { return ruled_rays < disputed_rays; }
};

// Dispute flags per ray: bit 0 closest hits differ, bit 1 any-hit answers differ.
inline constexpr std::uint8_t kClosestDisputed = 1, kOcclusionDisputed = 2;

ArbitrationResult arbitrate(const arbiter::Arbiter& arbiter, std::span<const Ray> rays,
                            std::span<const BackendAnswers> answers, std::span<const std::uint8_t> disputes,
                            std::size_t max_rays, std::size_t max_examples);

// Adds `part` into `total` (counts, maxima, and examples up to max_examples).
void accumulate(ArbiterTally& total, const ArbiterTally& part, std::size_t max_examples);

}  // namespace twinray::crosscheck
