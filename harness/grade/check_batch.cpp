// The batch-calls check: the plugin's optional intersect_batch / occluded_batch (twinray_plugin.h), judged
// answer by answer as the answer checks judge intersect1 / occluded1 (answers.h: the same reference, arbiter and
// tie rule). twinray calls the batch functions whenever a plugin has them (renders, crosscheck, every command,
// in process and isolated), while the other checks call the single-ray functions one ray at a time; a bug that
// lives only in the batch path (a hit record or a bound carried from one ray to the next, a lane mask, a loop
// that stops early) is caught here and nowhere else. Not applicable to a plugin without batch functions
// (grade_run.cpp: skipped, worth nothing); a plugin with only one of them has that one judged (the other query
// kind goes through its single-ray function, as twinray calls it).
//
// The rays mix what a batch must keep apart: hits followed by misses, closest and any-hit queries, every ray its
// own tmin and tmax (the ray-interval variants cut each ray just before and just after its first surface, and
// the interval-end rays end exactly at a crossing, judged strictly as in the ray-interval check), in a seeded
// shuffled order. They are handed over in batches whose sizes cycle through kBatchSizes: a single ray, a few,
// a SIMD-unfriendly count, the worker's call size (worker_protocol.h, kBatchCallRays) and one either side of
// it, and more than a worker request (kChunkRays) so one batch spans requests.

#include "backends/plugin/worker_protocol.h"
#include "core/geometry/ray_text.h"
#include "core/sampling/rng.h"
#include "harness/grade/answers.h"
#include "harness/grade/checks.h"
#include "harness/grade/grade_rays.h"
#include "harness/grade/interval_ends.h"

#include <fmt/core.h>

#include <algorithm>
#include <numeric>
#include <optional>

namespace twinray::grade {

namespace {

// Base rays when the suite gives no "count" (per kind); each that hits adds four interval variants.
constexpr std::size_t kDefaultBatchRays = 2000;

constexpr std::size_t kBatchSizes[] = {1,
                                       3,
                                       64,
                                       plugin_worker::kBatchCallRays - 1,
                                       plugin_worker::kBatchCallRays,
                                       plugin_worker::kBatchCallRays + 1,
                                       plugin_worker::kChunkRays + 7};

struct Batch {
  std::size_t begin = 0, size = 0;
};

// Consecutive batches covering [0, n), their sizes cycling through kBatchSizes.
std::vector<Batch> cut_into_batches(std::size_t n) {
  std::vector<Batch> batches;
  for (std::size_t begin = 0, k = 0; begin < n; ++k) {
    const std::size_t size = std::min(kBatchSizes[k % std::size(kBatchSizes)], n - begin);
    batches.push_back({begin, size});
    begin += size;
  }
  return batches;
}

}  // namespace

CheckVerdict run_batch_check(CheckContext& ctx) {
  const CheckSpec& spec = ctx.spec;
  const std::string reference = ctx.reference_name();
  const std::size_t count = ctx.count_or(kDefaultBatchRays);

  // Rays in set order: the kinds' rays, their interval variants, then the interval-end rays.
  std::vector<Ray> rays =
      ctx.rays_of_kinds({crosscheck::RayKind::Uniform, crosscheck::RayKind::Camera, crosscheck::RayKind::Shadow}, count);
  {
    const Answers first = trace_rays(ctx.scene.reference(reference), rays, Queries::Closest);
    const std::vector<Ray> variants = interval_rays(rays, first.hits);
    rays.insert(rays.end(), variants.begin(), variants.end());
  }
  const std::size_t judged = rays.size();
  const std::vector<IntervalEndRay> ends = unambiguous_ends(
      ctx.scene.arbiter(), interval_end_rays(ctx.scene.scene(), std::max<std::size_t>(1, count / 8), spec.seed));
  for (const IntervalEndRay& e : ends) rays.push_back(e.ray);

  // The order they are asked in: shuffled (seeded), so every batch mixes kinds, hits and misses, and intervals.
  std::vector<std::size_t> order(rays.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  Rng rng = Rng::keyed(spec.seed, 0xba7c, 1);
  for (std::size_t i = order.size(); i > 1; --i)
    std::swap(order[i - 1], order[rng.next_below(static_cast<std::uint32_t>(i))]);
  std::vector<Ray> asked(rays.size());
  for (std::size_t j = 0; j < order.size(); ++j) asked[j] = rays[order[j]];
  const std::vector<Batch> batches = cut_into_batches(asked.size());

  const bool intersect_batch = ctx.env.plugin.has_intersect_batch(), occluded_batch = ctx.env.plugin.has_occluded_batch();
  if (!intersect_batch && !occluded_batch)  // grade_run.cpp reports the check not applicable instead
    throw std::logic_error("the batch-calls check needs a plugin with a batch function");
  PluginInstance plugin = ctx.built_plugin();
  plugin.use_batch_functions();
  std::vector<Hit> hits(asked.size());
  std::vector<std::uint8_t> occluded(asked.size());
  for (const Batch& b : batches) {
    const std::span<const Ray> some(asked.data() + b.begin, b.size);
    (*plugin).intersect(some, std::span<Hit>(hits.data() + b.begin, b.size));
    (*plugin).occluded(some, std::span<std::uint8_t>(occluded.data() + b.begin, b.size));
  }
  plugin.end();

  // Back to set order, for judging.
  Answers mine, mine_at_ends;
  mine.hits.resize(judged);
  mine.occluded.resize(judged);
  mine_at_ends.hits.resize(ends.size());
  mine_at_ends.occluded.resize(ends.size());
  std::vector<std::size_t> position(rays.size());  // set index -> index in the order asked
  for (std::size_t j = 0; j < order.size(); ++j) {
    const std::size_t i = order[j];
    position[i] = j;
    Answers& into = i < judged ? mine : mine_at_ends;
    const std::size_t at = i < judged ? i : i - judged;
    into.hits[at] = hits[j];
    into.occluded[at] = occluded[j];
  }
  const std::span<const Ray> judged_rays(rays.data(), judged);
  const Answers expected = trace_rays(ctx.scene.reference(reference), judged_rays, Queries::Both);
  const Judgement j = judge(ctx.scene, judged_rays, mine, expected,
                            {Queries::Both, reference, ctx.env.plugin.traits().honours_ties, "plugin",
                             ctx.env.plugin.traits().watertight});
  const EndJudgement end_j = judge_ends(ends, mine_at_ends);

  const std::size_t answers = 2 * rays.size();
  const std::size_t wrong = j.wrong_total() + end_j.wrong;
  std::vector<std::string> functions;
  if (intersect_batch) functions.push_back("intersect_batch");
  if (occluded_batch) functions.push_back("occluded_batch");
  CheckVerdict v;
  v.passed = wrong == 0;
  v.figures = judgement_figures(j, rays.size(), answers, wrong, reference);
  v.figures["interval_end_rays"] = ends.size();
  v.figures["wrong_interval_ends"] = end_j.wrong;
  v.figures["batches"] = batches.size();
  v.figures["functions"] = functions;
  const std::string called = "through " + (functions.size() == 2 ? functions[0] + " and " + functions[1] : functions.at(0));
  if (v.passed) {
    v.detail = fmt::format("all {} answers {} right, in {} batches of 1 to {} rays{}", answers, called, batches.size(),
                           plugin_worker::kChunkRays + 7, summary_of_allowed(j));
    return v;
  }

  // The first wrong answer in the order asked, with its batch.
  std::size_t set_index = 0;
  bool any_hit = false;
  std::string description;
  if (j.wrong_total() > 0) {
    set_index = j.wrong.front().ray;
    any_hit = j.wrong.front().any_hit;
    description = j.first_wrong_description;
  }
  if (end_j.first && (j.wrong_total() == 0 || position[judged + *end_j.first] < position[set_index])) {
    set_index = judged + *end_j.first;
    any_hit = end_j.first_any_hit;
    description = end_j.first_description;
  }
  const std::size_t at = position[set_index];
  const auto batch = std::upper_bound(batches.begin(), batches.end(), at,
                                      [](std::size_t x, const Batch& b) { return x < b.begin; }) - 1;
  v.detail = fmt::format("{} of {} answers {} wrong ({:.3g}%); first, ray {} of a batch of {} ({} answer): {}", wrong,
                         answers, called, 100.0 * static_cast<double>(wrong) / static_cast<double>(answers),
                         at - batch->begin, batch->size, any_hit ? "any-hit" : "closest-hit", description);
  v.figures["first_wrong_ray"] = format_ray_hex(rays[set_index]);
  // `twinray trace` asks one ray through intersect1 and occluded1, which the other checks judge: the batch path
  // is replayed by rerunning this check. The single-ray functions' answer to the same ray says whether the bug
  // is the batch path's own.
  v.reproduce = ctx.grade_command();
  if (const std::optional<CheckContext::AloneAnswer> alone = ctx.answer_alone(rays[set_index])) {
    const bool same = any_hit ? alone->occluded == (occluded[at] != 0) : same_bits(alone->hit, hits[at]);
    v.figures["single_call_answers_same"] = same;
    if (!same)
      v.detail += fmt::format("; the single-ray function answers that ray {} (the bug is the batch path's)",
                              any_hit ? (alone->occluded ? "occluded" : "not occluded") : describe_hit(alone->hit));
  }
  return v;
}

}  // namespace twinray::grade
