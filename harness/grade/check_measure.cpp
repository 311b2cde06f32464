// performance: build time and closest-hit rays per second of the plugin against bvh and embree-fast on the
// same rays, on one thread each (the plugin's figure includes the round trips to its worker process), and
// nodes and primitives per ray when the plugin counts them. Reported always; worth points only when the
// suite sets thresholds. Wrong answers on the timed rays fail the check whatever the speed: a fast wrong
// answer is not fast.
//
// tree-quality: the SAH cost the plugin reports for its tree (tree_cost.h's model) against the reference
// builder's, and nodes and primitives per ray against bvh's, measured on the same rays.

#include "harness/grade/answers.h"
#include "harness/grade/checks.h"
#include "harness/grade/tree_cost.h"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace twinray::grade {

namespace {

constexpr std::size_t kDefaultPerformanceRays = 100000;
constexpr std::size_t kDefaultTreeRays = 20000;
constexpr int kTimedRuns = 2;  // the faster of two runs: the first also warms caches and the worker's pages

struct Timing {
  double rays_per_second = 0.0;
  QueryStats stats;  // of one run
};

Timing time_closest(const Backend& backend, std::span<const Ray> rays) {
  Timing t;
  std::vector<Hit> hits(rays.size());
  double best = INFINITY;
  for (int run = 0; run < kTimedRuns; ++run) {
    QueryStats stats;
    const auto start = std::chrono::steady_clock::now();
    backend.intersect(rays, std::span<Hit>(hits), &stats);
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    t.stats = stats;
  }
  t.rays_per_second = best > 0.0 ? static_cast<double>(rays.size()) / best : 0.0;
  return t;
}

double per_ray(std::uint64_t total, std::size_t rays) {
  return rays ? static_cast<double>(total) / static_cast<double>(rays) : 0.0;
}

// Appends "name value (limit)" to `failed` when a threshold is broken.
void require(std::optional<double> limit, bool at_most, double value, const char* what, std::vector<std::string>& failed) {
  if (!limit) return;
  if (at_most ? value <= *limit : value >= *limit) return;
  failed.push_back(
      fmt::format("{} {:.3g} {} {:.3g}", what, value, at_most ? "above the limit" : "below the minimum", *limit));
}

std::string join(const std::vector<std::string>& parts) {
  std::string s;
  for (const std::string& p : parts) s += (s.empty() ? "" : "; ") + p;
  return s;
}

}  // namespace

CheckVerdict run_performance_check(CheckContext& ctx) {
  const std::vector<Ray> rays = ctx.rays_of_kinds({crosscheck::RayKind::Camera, crosscheck::RayKind::Diffuse},
                                                  ctx.count_or(kDefaultPerformanceRays));
  // The references are timed before the plugin's worker starts: nothing it runs (a helper thread that spins)
  // can slow them and so flatter its own ratio.
  const Backend& bvh = ctx.scene.reference("bvh");
  const Backend& fast = ctx.scene.reference("embree-fast");
  const Timing theirs = time_closest(bvh, rays);
  const Timing embree = time_closest(fast, rays);
  PluginInstance plugin = ctx.built_plugin();
  const double build_seconds = plugin->build_stats().build_seconds;
  const Timing mine = time_closest(*plugin, rays);

  const Answers answers = trace_rays(*plugin, rays, Queries::Closest);
  plugin.end();
  const Answers expected = trace_rays(ctx.scene.reference("embree"), rays, Queries::Closest);
  const Judgement j = judge(ctx.scene, rays, answers, expected,
                            {Queries::Closest, "embree", ctx.env.plugin.traits().honours_ties, "plugin",
                             ctx.env.plugin.traits().watertight});

  const double vs_bvh = theirs.rays_per_second > 0.0 ? mine.rays_per_second / theirs.rays_per_second : 0.0;
  const double vs_fast = embree.rays_per_second > 0.0 ? mine.rays_per_second / embree.rays_per_second : 0.0;
  const bool counted = ctx.env.plugin.traits().counts_traversal;
  CheckVerdict v;
  v.scored = ctx.spec.thresholds.any();
  v.figures = {{"rays", rays.size()},
               {"build_seconds", {{"plugin", build_seconds},
                                  {"bvh", bvh.build_stats().build_seconds},
                                  {"embree-fast", fast.build_stats().build_seconds}}},
               {"rays_per_second", {{"plugin", mine.rays_per_second},
                                    {"bvh", theirs.rays_per_second},
                                    {"embree-fast", embree.rays_per_second}}},
               {"speed_vs_bvh", vs_bvh},
               {"speed_vs_embree_fast", vs_fast},
               {"wrong", j.wrong_total()}};
  if (counted) {
    v.figures["nodes_per_ray"] = {{"plugin", per_ray(mine.stats.nodes_visited, rays.size())},
                                  {"bvh", per_ray(theirs.stats.nodes_visited, rays.size())}};
    v.figures["primitives_per_ray"] = {{"plugin", per_ray(mine.stats.primitives_tested, rays.size())},
                                       {"bvh", per_ray(theirs.stats.primitives_tested, rays.size())}};
  }

  std::vector<std::string> failed;
  require(ctx.spec.thresholds.min_speed_vs_bvh, false, vs_bvh, "speed vs bvh", failed);
  require(ctx.spec.thresholds.min_speed_vs_embree_fast, false, vs_fast, "speed vs embree-fast", failed);
  require(ctx.spec.thresholds.max_build_seconds, true, build_seconds, "build seconds", failed);
  if (j.wrong_total() != 0)
    failed.insert(failed.begin(), fmt::format("{} of the timed rays answered wrong", j.wrong_total()));
  v.passed = failed.empty();
  const std::string figures = fmt::format("{:.3g} Mrays/s, {:.2f}x bvh, {:.2f}x embree-fast, build {:.3f} s",
                                          mine.rays_per_second * 1e-6, vs_bvh, vs_fast, build_seconds);
  v.detail = v.passed ? figures : figures + ": " + join(failed);
  if (!v.passed) v.reproduce = ctx.grade_command();
  return v;
}

CheckVerdict run_tree_quality_check(CheckContext& ctx) {
  PluginInstance plugin = ctx.built_plugin();
  const double reported = plugin->build_stats().sah_cost;
  const double reference = reference_sah_cost(ctx.scene.geometry());
  const std::vector<Ray> rays = ctx.rays_of_kinds({crosscheck::RayKind::Camera, crosscheck::RayKind::Diffuse},
                                                  ctx.count_or(kDefaultTreeRays));
  const bool counted = ctx.env.plugin.traits().counts_traversal;
  const Answers mine = trace_rays(*plugin, rays, Queries::Closest);
  plugin.end();
  const Answers theirs = trace_rays(ctx.scene.reference("bvh"), rays, Queries::Closest);
  const double nodes = per_ray(mine.stats.nodes_visited, rays.size());
  const double prims = per_ray(mine.stats.primitives_tested, rays.size());
  const double ref_nodes = per_ray(theirs.stats.nodes_visited, rays.size());
  const double ref_prims = per_ray(theirs.stats.primitives_tested, rays.size());
  const double sah_ratio = reference > 0.0 ? reported / reference : 0.0;
  // Every tree over at least one primitive costs at least 1 in the unit model (plugin-abi.md): its root, as an
  // interior node (A(root) / A(root)) or as a leaf of N >= 1 primitives. A reported cost below that (or not a
  // number) describes no tree of this scene, and must not pass a threshold as a small ratio would.
  const bool has_primitives = ctx.scene.geometry().triangle_count() + ctx.scene.geometry().sphere_count() > 0;
  const bool impossible_sah = reported != 0.0 && has_primitives && !(reported >= 1.0 && std::isfinite(reported));

  CheckVerdict v;
  v.scored = ctx.spec.thresholds.any();
  v.figures = {{"sah_cost", {{"plugin", reported > 0.0 ? nlohmann::json(reported) : nlohmann::json(nullptr)},
                             {"reference", reference}}},
               {"sah_ratio", reported > 0.0 ? nlohmann::json(sah_ratio) : nlohmann::json(nullptr)},
               {"rays", rays.size()}};
  if (counted) {
    v.figures["nodes_per_ray"] = {{"plugin", nodes}, {"bvh", ref_nodes}};
    v.figures["primitives_per_ray"] = {{"plugin", prims}, {"bvh", ref_prims}};
  }

  // Messages built with fmt: GCC 12 reports a bogus -Warray-bounds for a string literal pushed into a vector.
  std::vector<std::string> failed;
  const Thresholds& t = ctx.spec.thresholds;
  if (t.max_sah_ratio && impossible_sah)
    failed.push_back(fmt::format("the plugin reports an SAH cost of {}, which no tree of this scene has (the root alone "
                                 "costs 1)", reported));
  else if (t.max_sah_ratio && !(reported > 0.0))
    failed.push_back(fmt::format("the plugin reports no SAH cost ({})", "twinray_build_stats::sah_cost"));
  else
    require(t.max_sah_ratio, true, sah_ratio, "SAH cost ratio", failed);
  if ((t.max_nodes_per_ray_ratio || t.max_primitives_per_ray_ratio) && !counted) {
    failed.push_back(fmt::format("the plugin does not count its traversal ({})", "TWINRAY_PLUGIN_COUNTS_TRAVERSAL"));
  } else {
    require(t.max_nodes_per_ray_ratio, true, ref_nodes > 0.0 ? nodes / ref_nodes : 0.0, "nodes per ray ratio", failed);
    require(t.max_primitives_per_ray_ratio, true, ref_prims > 0.0 ? prims / ref_prims : 0.0, "primitives per ray ratio", failed);
  }
  v.passed = failed.empty();
  std::string figures = impossible_sah ? fmt::format("an impossible SAH cost of {} reported (the reference's is {:.4g})",
                                                    reported, reference)
                       : reported > 0.0 ? fmt::format("SAH cost {:.4g} against the reference's {:.4g} ({:.2f}x)", reported,
                                                     reference, sah_ratio)
                                       : fmt::format("no SAH cost reported (the reference's is {:.4g})", reference);
  if (counted)
    figures += fmt::format(", {:.1f} nodes and {:.1f} primitives per ray against bvh's {:.1f} and {:.1f}", nodes, prims,
                           ref_nodes, ref_prims);
  v.detail = v.passed ? figures : figures + ": " + join(failed);
  if (!v.passed) v.reproduce = ctx.grade_command();
  return v;
}

}  // namespace twinray::grade
