#pragma once
// Tracing a ray set through a backend, and judging the plugin's answers against the reference's.
//
// Judging (docs/grading.md, "What counts as wrong"): every ray is classified as crosscheck classifies it
// (harness/crosscheck/hit_comparison.h). A genuine disagreement is wrong unless a second opinion overrules
// the reference: the other built-in oracle (brute when the reference is embree, embree when it is brute)
// answers the same ray, and if the plugin agrees with it, the reference erred and the plugin is right.
// Edge disagreements are never wrong here (the watertight checks test leaks where a miss is unambiguous).
// A tie disagreement is wrong only under the tie rule (a plugin that claims it, or a ties check) and only
// between two geometrically identical primitives (the same vertices in the same order, or the same sphere):
// there every correct float intersector computes bit-identical t, so the lower (geom_id, prim_id) must win.
// Two different primitives that meet at (nearly) the same t are a tie only up to rounding, which no rule
// can referee.

#include "core/backend/backend.h"
#include "harness/grade/grade_scene.h"

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
  std::size_t edge = 0, tie = 0;  // disagreements that are not wrong
  std::size_t overruled = 0;      // genuine disagreements where the second opinion sided with the plugin
  std::size_t unarbitrated = 0;   // genuine disagreements beyond the arbitration cap, counted as wrong
  std::vector<WrongAnswer> wrong; // every wrong answer, in ray order
  std::string second_opinion;     // the backend that ruled ("brute", "embree")

  std::size_t wrong_total() const { return wrong_closest + wrong_any; }
  // The first wrong answer, described in one line ("plugin misses, embree hits geom 0 prim 12 at t 2.5").
  std::string first_wrong_description;
};

struct JudgeOptions {
  Queries queries = Queries::Both;
  std::string reference;          // "embree" or "brute"
  bool tie_rule = false;  // judge ties between identical primitives (see above)
  std::string plugin_label = "plugin";
  // At most this many genuine disagreements are put to the second opinion; beyond it a plugin is plainly
  // wrong on many rays, and a second opinion per ray would cost O(rays * primitives) with brute.
  std::size_t max_arbitrations = 2000;
};

Judgement judge(GradeScene& scene, std::span<const Ray> rays, const Answers& plugin, const Answers& reference,
                const JudgeOptions& options);

// "geom 0 prim 12 at t 2.5 (0x1.4p+1)" or "a miss".
std::string describe_hit(const Hit& hit);

}  // namespace twinray::grade
