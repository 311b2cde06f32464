// performance: build time and closest-hit rays per second of the plugin against bvh and embree-fast on the
// same rays, on one thread each (the plugin's figure includes the round trips to its worker process), through
// its single-ray functions and, when it has them, its batch functions (the path twinray's renders take, and the
// one thresholds judge then); any-hit rays per second too, and both per ray kind; and
// nodes and primitives per ray when the plugin counts them. Reported always; worth points only when the
// suite sets thresholds. Wrong answers on the timed rays fail the check whatever the speed: a fast wrong
// answer is not fast.
//
// tree-quality: the SAH cost the plugin reports for its tree (tree_cost.h's model) against the reference
// builder's, and nodes and primitives per ray against bvh's, measured on the same rays.

#include "harness/grade/answers.h"
#include "harness/grade/checks.h"
#include "harness/grade/grade_rays.h"
#include "harness/grade/timed_query.h"
#include "harness/grade/tree_cost.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

namespace twinray::grade {

namespace {

constexpr std::size_t kDefaultPerformanceRays = 100000;
constexpr std::size_t kDefaultTreeRays = 20000;
constexpr int kTimedRuns = 2;  // the faster of two runs: the first also warms caches and the worker's pages

struct Timing {
  double seconds = 0.0;      // the faster run
  double cpu_seconds = 0.0;  // the run with less CPU time (timed_query.h); negative when unreadable
  QueryStats stats;          // of one run
};

// Closest hits (any_hit false) or any-hit answers of `rays`, timed kTimedRuns times.
Timing time_query(const Backend& backend, std::span<const Ray> rays, bool any_hit) {
  Timing t;
  t.seconds = INFINITY;
  t.cpu_seconds = INFINITY;
  bool has_cpu = true;
  for (int run = 0; run < kTimedRuns; ++run) {
    const RunTime r = time_run(backend, rays, any_hit, t.stats);
    t.seconds = std::min(t.seconds, r.wall);
    t.cpu_seconds = std::min(t.cpu_seconds, r.cpu);
    has_cpu = has_cpu && r.has_cpu();
  }
  if (!has_cpu) t.cpu_seconds = -1.0;
  return t;
}

double rate(std::size_t rays, double seconds) { return seconds > 0.0 ? static_cast<double>(rays) / seconds : 0.0; }
double ratio(double a, double b) { return b > 0.0 ? a / b : 0.0; }

// One ray kind's rays, and the seconds each timed path took on them, closest hit [0] and any hit [1].
enum Path { kBvh, kEmbreeFast, kPlugin, kPluginBatch, kPaths };
constexpr const char* kPathNames[kPaths] = {"bvh", "embree-fast", "plugin", "plugin_batch"};
struct KindTimes {
  crosscheck::RayKind kind;
  std::vector<Ray> rays;
  Timing times[kPaths][2];
};

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
  const std::size_t count = ctx.count_or(kDefaultPerformanceRays);
  const std::vector<crosscheck::RayKind> kinds =
      ctx.spec.rays.empty() ? std::vector<crosscheck::RayKind>{crosscheck::RayKind::Camera, crosscheck::RayKind::Diffuse}
                            : ctx.spec.rays;
  std::vector<KindTimes> per_kind;
  std::vector<Ray> rays;
  for (const crosscheck::RayKind k : kinds) {
    KindTimes kt{k, kind_rays(k, ctx.scene.scene(), ctx.scene.reference("embree"), count, ctx.spec.seed), {}};
    rays.insert(rays.end(), kt.rays.begin(), kt.rays.end());
    per_kind.push_back(std::move(kt));
  }
  // The references are timed before the plugin's worker starts: nothing it runs (a helper thread that spins)
  // can slow them and so flatter its own ratio.
  const Backend& bvh = ctx.scene.reference("bvh");
  const Backend& fast = ctx.scene.reference("embree-fast");
  for (KindTimes& kt : per_kind)
    for (int q = 0; q < 2; ++q) {
      kt.times[kBvh][q] = time_query(bvh, kt.rays, q == 1);
      kt.times[kEmbreeFast][q] = time_query(fast, kt.rays, q == 1);
    }
  PluginInstance plugin = ctx.built_plugin();
  const double build_seconds = plugin->build_stats().build_seconds;
  // The single-ray functions (every plugin has them; the figures' meaning since the first round), then, for a
  // plugin with batch functions, the path twinray's renders and crosscheck take: its batch calls. A query the
  // plugin has no batch function for goes through its single-ray function on that path too, as twinray calls it.
  const bool has_batch = ctx.env.plugin.has_intersect_batch() || ctx.env.plugin.has_occluded_batch();
  for (KindTimes& kt : per_kind)
    for (int q = 0; q < 2; ++q) kt.times[kPlugin][q] = time_query(*plugin, kt.rays, q == 1);
  if (has_batch) {
    plugin.use_batch_functions();
    for (KindTimes& kt : per_kind)
      for (int q = 0; q < 2; ++q) kt.times[kPluginBatch][q] = time_query(*plugin, kt.rays, q == 1);
    plugin.use_single_calls();
  }

  const Answers answers = trace_rays(*plugin, rays, Queries::Closest);
  plugin.end();
  const Answers expected = trace_rays(ctx.scene.reference("embree"), rays, Queries::Closest);
  const Judgement j = judge(ctx.scene, rays, answers, expected,
                            {Queries::Closest, "embree", ctx.env.plugin.traits().honours_ties, "plugin",
                             ctx.env.plugin.traits().watertight});

  // Totals over the kinds: rays over the sum of each kind's fastest run.
  double seconds[kPaths][2] = {};
  double cpu[kPaths][2] = {};  // the same in CPU time (timed_query.h)
  bool has_cpu = true;         // every timed path's CPU time could be read
  QueryStats stats[kPaths];
  for (const KindTimes& kt : per_kind)
    for (int p = 0; p < kPaths; ++p) {
      for (int q = 0; q < 2; ++q) {
        seconds[p][q] += kt.times[p][q].seconds;
        cpu[p][q] += kt.times[p][q].cpu_seconds;
        if ((p != kPluginBatch || has_batch) && kt.times[p][q].cpu_seconds < 0.0) has_cpu = false;
      }
      stats[p].nodes_visited += kt.times[p][0].stats.nodes_visited;
      stats[p].primitives_tested += kt.times[p][0].stats.primitives_tested;
    }
  const auto rates = [&](int q, double const (&s)[kPaths][2], std::size_t n) {
    nlohmann::json r = nlohmann::json::object();
    for (int p = 0; p < kPaths; ++p)
      r[kPathNames[p]] = p == kPluginBatch && !has_batch ? nlohmann::json(nullptr) : nlohmann::json(rate(n, s[p][q]));
    return r;
  };
  const double mine = rate(rays.size(), seconds[kPlugin][0]);
  const double mine_batch = rate(rays.size(), seconds[kPluginBatch][0]);
  const double theirs = rate(rays.size(), seconds[kBvh][0]);
  const double embree = rate(rays.size(), seconds[kEmbreeFast][0]);
  const double vs_bvh = ratio(mine, theirs), vs_fast = ratio(mine, embree);
  const double vs_bvh_batch = ratio(mine_batch, theirs), vs_fast_batch = ratio(mine_batch, embree);
  // The same ratios in CPU time: the plugin's worker's (every thread of it) against the references' calling
  // thread's, so a busy machine moves them less and a plugin's own threads are charged, not free.
  const double cpu_vs_bvh = ratio(cpu[kBvh][0], cpu[kPlugin][0]), cpu_vs_fast = ratio(cpu[kEmbreeFast][0], cpu[kPlugin][0]);
  const double cpu_vs_bvh_batch = ratio(cpu[kBvh][0], cpu[kPluginBatch][0]);
  const double cpu_vs_fast_batch = ratio(cpu[kEmbreeFast][0], cpu[kPluginBatch][0]);
  // Thresholds judge the path twinray takes: the batch calls when the plugin has intersect_batch; in CPU time
  // when every CPU time could be read (docs/grading.md, "The thirteenth round: CPU time").
  const bool judge_batch = ctx.env.plugin.has_intersect_batch();
  const double judged_vs_bvh = has_cpu ? (judge_batch ? cpu_vs_bvh_batch : cpu_vs_bvh) : (judge_batch ? vs_bvh_batch : vs_bvh);
  const double judged_vs_fast =
      has_cpu ? (judge_batch ? cpu_vs_fast_batch : cpu_vs_fast) : (judge_batch ? vs_fast_batch : vs_fast);
  const double any_mine = rate(rays.size(), seconds[kPlugin][1]);
  const double any_mine_batch = rate(rays.size(), seconds[kPluginBatch][1]);
  const double any_theirs = rate(rays.size(), seconds[kBvh][1]);
  const bool counted = ctx.env.plugin.traits().counts_traversal;
  const auto or_null = [&](double x) { return has_batch ? nlohmann::json(x) : nlohmann::json(nullptr); };

  CheckVerdict v;
  v.scored = ctx.spec.thresholds.any();
  v.figures = {{"rays", rays.size()},
               {"build_seconds", {{"plugin", build_seconds},
                                  {"bvh", bvh.build_stats().build_seconds},
                                  {"embree-fast", fast.build_stats().build_seconds}}},
               {"rays_per_second", rates(0, seconds, rays.size())},
               {"speed_vs_bvh", vs_bvh},
               {"speed_vs_embree_fast", vs_fast},
               {"speed_vs_bvh_batch", or_null(vs_bvh_batch)},
               {"speed_vs_embree_fast_batch", or_null(vs_fast_batch)},
               {"judged_path", judge_batch ? "batch" : "single"},
               {"any_hit", {{"rays_per_second", rates(1, seconds, rays.size())},
                            {"speed_vs_bvh", ratio(any_mine, any_theirs)},
                            {"speed_vs_bvh_batch", or_null(ratio(any_mine_batch, any_theirs))}}},
               {"wrong", j.wrong_total()}};
  if (has_cpu) {
    v.figures["cpu_rays_per_second"] = rates(0, cpu, rays.size());
    v.figures["cpu_speed_vs_bvh"] = cpu_vs_bvh;
    v.figures["cpu_speed_vs_embree_fast"] = cpu_vs_fast;
    v.figures["cpu_speed_vs_bvh_batch"] = or_null(cpu_vs_bvh_batch);
    v.figures["cpu_speed_vs_embree_fast_batch"] = or_null(cpu_vs_fast_batch);
    v.figures["any_hit"]["cpu_rays_per_second"] = rates(1, cpu, rays.size());
  }
  v.figures["judged_time"] = has_cpu ? "cpu" : "wall";
  nlohmann::json kinds_json = nlohmann::json::object();
  for (const KindTimes& kt : per_kind) {
    double s[kPaths][2];
    for (int p = 0; p < kPaths; ++p)
      for (int q = 0; q < 2; ++q) s[p][q] = kt.times[p][q].seconds;
    kinds_json[std::string(crosscheck::to_string(kt.kind))] = {{"closest", rates(0, s, kt.rays.size())},
                                                               {"any", rates(1, s, kt.rays.size())}};
  }
  v.figures["per_kind"] = kinds_json;
  if (counted) {
    v.figures["nodes_per_ray"] = {{"plugin", per_ray(stats[kPlugin].nodes_visited, rays.size())},
                                  {"bvh", per_ray(stats[kBvh].nodes_visited, rays.size())}};
    v.figures["primitives_per_ray"] = {{"plugin", per_ray(stats[kPlugin].primitives_tested, rays.size())},
                                       {"bvh", per_ray(stats[kBvh].primitives_tested, rays.size())}};
  }

  std::vector<std::string> failed;
  const std::string path = fmt::format("{}{}", has_cpu ? " in CPU time" : "", judge_batch ? " (batch calls)" : "");
  require(ctx.spec.thresholds.min_speed_vs_bvh, false, judged_vs_bvh, fmt::format("speed vs bvh{}", path).c_str(), failed);
  require(ctx.spec.thresholds.min_speed_vs_embree_fast, false, judged_vs_fast,
          fmt::format("speed vs embree-fast{}", path).c_str(), failed);
  require(ctx.spec.thresholds.max_build_seconds, true, build_seconds, "build seconds", failed);
  if (j.wrong_total() != 0)
    failed.insert(failed.begin(), fmt::format("{} of the timed rays answered wrong", j.wrong_total()));
  v.passed = failed.empty();
  std::string figures = fmt::format("{:.3g} Mrays/s, {:.2f}x bvh, {:.2f}x embree-fast", mine * 1e-6, vs_bvh, vs_fast);
  if (has_batch) figures += fmt::format("; batch calls {:.3g} Mrays/s, {:.2f}x bvh", mine_batch * 1e-6, vs_bvh_batch);
  if (has_cpu) figures += fmt::format("; in CPU time {:.2f}x bvh", judge_batch ? cpu_vs_bvh_batch : cpu_vs_bvh);
  figures += fmt::format("; any hit {:.2f}x bvh, build {:.3f} s", ratio(any_mine, any_theirs), build_seconds);
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
  // The same rays' any-hit queries, counted apart: a walk that goes on after its first hit (threaded_bvh.c bug
  // 8) or visits boxes beyond tmax answers right and only these figures show it.
  // Only a plugin that counts has figures to show, so the others are not asked (brute force's calls are slow).
  const Answers mine_any = counted ? trace_rays(*plugin, rays, Queries::Any) : Answers{};
  plugin.end();
  const Answers theirs = trace_rays(ctx.scene.reference("bvh"), rays, Queries::Closest);
  const Answers theirs_any = counted ? trace_rays(ctx.scene.reference("bvh"), rays, Queries::Any) : Answers{};
  const double nodes = per_ray(mine.stats.nodes_visited, rays.size());
  const double prims = per_ray(mine.stats.primitives_tested, rays.size());
  const double ref_nodes = per_ray(theirs.stats.nodes_visited, rays.size());
  const double ref_prims = per_ray(theirs.stats.primitives_tested, rays.size());
  const double any_nodes = per_ray(mine_any.stats.nodes_visited, rays.size());
  const double any_prims = per_ray(mine_any.stats.primitives_tested, rays.size());
  const double ref_any_nodes = per_ray(theirs_any.stats.nodes_visited, rays.size());
  const double ref_any_prims = per_ray(theirs_any.stats.primitives_tested, rays.size());
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
    v.figures["any_hit"] = {{"nodes_per_ray", {{"plugin", any_nodes}, {"bvh", ref_any_nodes}}},
                            {"primitives_per_ray", {{"plugin", any_prims}, {"bvh", ref_any_prims}}}};
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
    figures += fmt::format(", {:.1f} nodes and {:.1f} primitives per ray against bvh's {:.1f} and {:.1f} (any hit {:.1f} "
                           "and {:.1f} against {:.1f} and {:.1f})",
                           nodes, prims, ref_nodes, ref_prims, any_nodes, any_prims, ref_any_nodes, ref_any_prims);
  v.detail = v.passed ? figures : figures + ": " + join(failed);
  if (!v.passed) v.reproduce = ctx.grade_command();
  return v;
}

}  // namespace twinray::grade
