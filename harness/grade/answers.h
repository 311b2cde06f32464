#pragma once
// Tracing a ray set through a backend, and judging the plugin's answers against the reference's.
//
// Judging (docs/grading.md, "What counts as wrong"): every ray is classified as crosscheck classifies it
// (harness/crosscheck/hit_comparison.h), and every disagreement with the reference is ruled by the arbiter
// (harness/arbiter/arbiter.h: the plugin's answer against exact arithmetic), so a correct answer is never
// marked wrong because the reference (robust Embree) erred on that ray, and a wrong one never passes because
// it lies near an edge. The arbiter holds the plugin to what it claims: a plugin that claims watertightness
// may hand an edge crossing to either neighbour but may not lose it; one that does not may also miss there.
// Ties are judged by the tie rule alone, and only between two geometrically identical primitives (the same
// vertices in the same order, or the same sphere): there every correct float intersector computes
// bit-identical t, so the lower (geom_id, prim_id) must win. Two different primitives that meet at (nearly)
// the same t tie only up to the rounding of each intersector's own t, which a plugin is not required to
// round correctly, so the arbiter's stricter tie rule (for backends with correctly rounded t) is not applied.

#include "core/backend/backend.h"
#include "harness/grade/grade_scene.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace twinray::grade {

struct Answers {
  std::vector<Hit> hits;
  std::vector<std::uint8_t> occluded;
  QueryStats stats;
};

enum class Queries { Closest, Any, Both };

// One call per query kind over the whole span (the plugin backend batches it).
Answers trace_rays(const Backend& backend, std::span<const Ray> rays, Queries queries);

struct WrongAnswer {
  std::size_t ray = 0;
  bool any_hit = false;  // the any-hit answer is wrong (else the closest hit)
};

struct Judgement {
  std::size_t rays = 0;
  std::size_t wrong_closest = 0, wrong_any = 0;
  std::size_t wrong_attributes = 0;  // of wrong_closest: the right hit with wrong u, v or ng (hit_attributes.h)
  std::size_t edge = 0, tie = 0;  // disagreements that are not wrong (the arbiter's reason, or the tie rule)
  std::size_t overruled = 0;      // disagreements where the arbiter ruled the plugin right and the reference wrong
  std::size_t unarbitrated = 0;   // genuine disagreements beyond the arbitration cap, counted as wrong
  std::size_t ruled = 0;          // disagreements put to the arbiter
  std::vector<WrongAnswer> wrong; // every wrong answer, in ray order
  std::string second_opinion = "exact";  // who rules disagreements (the arbiter's exact backend)

  std::size_t wrong_total() const { return wrong_closest + wrong_any; }
  // The first wrong answer, described in one line ("plugin misses, embree hits geom 0 prim 12 at t 2.5").
  std::string first_wrong_description;
};

struct JudgeOptions {
  Queries queries = Queries::Both;
  std::string reference;          // "embree" or "brute"
  bool tie_rule = false;  // judge ties between identical primitives (see above)
  std::string plugin_label = "plugin";
  bool watertight = false;  // the plugin claims watertightness: the arbiter does not excuse lost edge crossings
  // At most this many disagreements are put to the arbiter (a few microseconds to a millisecond each);
  // beyond it a plugin is plainly wrong on many rays, and the remaining genuine disagreements count as wrong.
  std::size_t max_arbitrations = 20000;
};

Judgement judge(GradeScene& scene, std::span<const Ray> rays, const Answers& plugin, const Answers& reference,
                const JudgeOptions& options);

// The figures every answer check reports of its judgement (the JSON report's per-check "figures"): `rays`,
// `answers`, `wrong` (all wrong answers the check counts, `j`'s and any others) and j's counts by kind.
nlohmann::json judgement_figures(const Judgement& j, std::size_t rays, std::size_t answers, std::size_t wrong,
                                 const std::string& reference);

// " (disagreements allowed: 3 edge, 1 tie)" for a check's detail, or "" when every answer agreed.
std::string summary_of_allowed(const Judgement& j);

// "geom 0 prim 12 at t 2.5 (0x1.4p+1)" or "a miss".
std::string describe_hit(const Hit& hit);

// The same hit to the bit: ids, t, u, v and ng (two misses are the same).
bool same_bits(const Hit& a, const Hit& b);

}  // namespace twinray::grade
