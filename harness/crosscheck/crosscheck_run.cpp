#include "harness/crosscheck/crosscheck_run.h"

#include "harness/scenes/named_scene.h"

#include "backends/registry.h"
#include "harness/arbiter/arbiter.h"
#include "harness/arbiter/tolerances.h"
#include "harness/crosscheck/arbitration.h"
#include "harness/crosscheck/hit_attributes.h"
#include "harness/crosscheck/hit_comparison.h"
#include "harness/crosscheck/ray_generation.h"
#include "core/scene/scene_loader.h"
#include "core/util/fp_mode.h"
#include "core/util/progress.h"

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <span>
#include <stdexcept>

namespace twinray::crosscheck {

namespace {

struct BackendRun {
  double seconds_closest = 0.0;
  double seconds_any = 0.0;
  std::size_t hits = 0;
  std::size_t any_closest_disagreements = 0;  // occluded() != intersect().found() within one backend
  std::vector<Hit> closest;
  std::vector<std::uint8_t> occluded;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

BackendRun trace(const Backend& backend, const std::vector<Ray>& rays) {
  BackendRun run;
  run.closest.resize(rays.size());
  run.occluded.resize(rays.size());
  // Timed on the calling thread only: per-thread throughput is what the ratios compare.
  auto start = std::chrono::steady_clock::now();
  backend.intersect(std::span<const Ray>(rays), std::span<Hit>(run.closest));
  run.seconds_closest = seconds_since(start);
  start = std::chrono::steady_clock::now();
  backend.occluded(std::span<const Ray>(rays), std::span<std::uint8_t>(run.occluded));
  run.seconds_any = seconds_since(start);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    run.hits += run.closest[i].found() ? 1 : 0;
    run.any_closest_disagreements += (run.occluded[i] != 0) != run.closest[i].found() ? 1 : 0;
  }
  return run;
}

// Closest hits whose u, v or ng break the conventions (hit_attributes.h), with the first few.
struct AttributeTally {
  std::size_t wrong = 0;
  std::vector<std::pair<std::size_t, std::string>> examples;  // ray index, why
};

constexpr std::size_t kAttributeExamples = 3;

AttributeTally rule_every_attribute(const GeometryIndex& index, const std::vector<Ray>& rays, const std::vector<Hit>& hits) {
  AttributeTally t;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (!hits[i].found()) continue;
    const AttributeRuling r = rule_attributes(index, rays[i], hits[i]);
    if (r.right) continue;
    ++t.wrong;
    if (t.examples.size() < kAttributeExamples) t.examples.emplace_back(i, r.detail);
  }
  return t;
}

double rate(std::size_t n, double seconds) { return seconds > 0.0 ? static_cast<double>(n) / seconds : 0.0; }

std::string describe_hit(const Hit& h) {
  if (!h.found()) return "miss";
  return fmt::format("geom {} prim {} t={:.9g} uv=({:.6g},{:.6g})", h.geom_id, h.prim_id, h.t, h.u, h.v);
}

// The ray in exact bits (C99 hex floats), so that it can be replayed.
std::string hex_ray(const Ray& r) {
  return fmt::format("org ({:a}, {:a}, {:a}) dir ({:a}, {:a}, {:a}) t [{:a}, {:a}]", r.org.x, r.org.y, r.org.z, r.dir.x,
                     r.dir.y, r.dir.z, r.tmin, r.tmax);
}

nlohmann::json ray_json(const Ray& r) {
  return {{"org", {r.org.x, r.org.y, r.org.z}}, {"dir", {r.dir.x, r.dir.y, r.dir.z}}, {"tmin", r.tmin},
          {"tmax", r.tmax}, {"hex", hex_ray(r)}};
}

nlohmann::json hit_json(const Hit& h) {
  if (!h.found()) return nullptr;
  return {{"geom_id", h.geom_id}, {"prim_id", h.prim_id}, {"t", h.t}, {"u", h.u}, {"v", h.v}};
}

constexpr std::size_t kWrongExamples = 5;

nlohmann::json reasons_json(const ArbiterTally& t) {
  nlohmann::json j = nlohmann::json::object();
  for (std::size_t k = 0; k < arbiter::kReasonCount; ++k)
    j[std::string(arbiter::to_string(static_cast<arbiter::Reason>(k)))] = t.reasons[k];
  return j;
}

nlohmann::json tally_json(const ArbiterTally& t) {
  nlohmann::json examples = nlohmann::json::array();
  for (const WrongAnswer& w : t.examples)
    examples.push_back({{"ray_index", w.ray_index},
                        {"ray", ray_json(w.ray)},
                        {"query", w.occlusion ? "any" : "closest"},
                        {"answer", w.occlusion ? nlohmann::json(w.answered_occluded) : hit_json(w.answer)},
                        {"exact", w.occlusion ? nlohmann::json(w.ruling.exact_occluded) : hit_json(w.ruling.exact)},
                        {"reason", arbiter::to_string(w.ruling.reason)},
                        {"detail", w.ruling.detail}});
  return {{"ruled", t.ruled}, {"wrong", t.wrong}, {"max_t_rel_error", t.max_t_rel_error}, {"reasons", reasons_json(t)},
          {"wrong_examples", examples}};
}

std::string wrong_reasons_text(const ArbiterTally& t) {
  std::string s;
  for (std::size_t k = 0; k < arbiter::kReasonCount; ++k) {
    const auto reason = static_cast<arbiter::Reason>(k);
    if (arbiter::is_wrong(reason) && t.reasons[k] > 0)
      s += fmt::format("{}{} {}", s.empty() ? "" : ", ", arbiter::to_string(reason), t.reasons[k]);
  }
  return s.empty() ? "-" : s;
}

}  // namespace

CrosscheckReport run_crosscheck(const CrosscheckSettings& settings) {
  const std::vector<std::string>& names = settings.backends;
  if (names.size() < 2) throw std::invalid_argument("--backends needs at least two backends to compare");

  const ScopedFlushDenormals ftz;
  // A file, $TWINRAY_SHARED/..., or procedural:KIND[:ARG]... (harness/scenes/named_scene.h), as `trace` takes.
  const Scene scene = load_named_scene(settings.scene.string());
  const GeometryIndex index(scene.geometry);

  fmt::print("scene {}: {} triangles, {} spheres ({} degenerate triangles skipped)\n", scene.source.string(),
             scene.geometry.triangle_count(), scene.geometry.sphere_count(), scene.report.degenerate_triangles);

  std::vector<std::unique_ptr<Backend>> backends;
  nlohmann::json j_build = nlohmann::json::object();
  for (const std::string& name : names) {
    backends.push_back(make_backend(name));
    backends.back()->build(scene.geometry);
    const BuildStats bs = backends.back()->build_stats();
    fmt::print("built {:<12} in {:8.3f} s, {:8.2f} MiB\n", name, bs.build_seconds,
               static_cast<double>(bs.memory_bytes) / (1024.0 * 1024.0));
    std::fflush(stdout);
    j_build[name] = {{"build_seconds", bs.build_seconds}, {"memory_bytes", bs.memory_bytes}};
  }

  // Rays that start on surfaces (diffuse, shadow) are built from first hits. They come from a built-in backend,
  // so a plugin under test never shapes the rays it is judged on.
  const Backend* hit_source = nullptr;
  std::unique_ptr<Backend> own_hit_source;
  const std::vector<std::string> builtin = backend_names();
  for (std::size_t k = 0; k < names.size() && hit_source == nullptr; ++k)
    if (std::find(builtin.begin(), builtin.end(), names[k]) != builtin.end()) hit_source = backends[k].get();
  if (hit_source == nullptr) {
    own_hit_source = make_backend("embree");
    own_hit_source->build(scene.geometry);
    hit_source = own_hit_source.get();
  }

  // The arbiter's exact backend is built once; it rules the disputed rays of every kind.
  std::unique_ptr<arbiter::Arbiter> arbiter;
  if (settings.arbitrate) {
    const auto arbiter_start = std::chrono::steady_clock::now();
    arbiter = std::make_unique<arbiter::Arbiter>(scene.geometry);
    fmt::print("built {:<12} in {:8.3f} s (arbiter)\n", "exact", seconds_since(arbiter_start));
    std::fflush(stdout);
  }
  std::vector<ArbiterTally> arbiter_totals(backends.size());
  std::size_t arbiter_disputed = 0, arbiter_ruled_rays = 0;
  double arbiter_seconds = 0.0;
  std::vector<std::string> capped_kinds;

  Progress progress("crosscheck", settings.kinds.size() * backends.size());
  std::size_t total_rays = 0, total_identical = 0, total_genuine = 0, total_wrong_attributes = 0;
  std::vector<std::size_t> wrong_attributes(backends.size(), 0);
  std::vector<double> closest_seconds(backends.size(), 0.0);
  std::vector<std::size_t> closest_rays(backends.size(), 0);
  nlohmann::json j_kinds = nlohmann::json::object();
  std::string report;

  for (const RayKind kind : settings.kinds) {
    const std::vector<Ray> rays = generate_rays(kind, scene, *hit_source, settings.rays_per_kind, settings.seed);
    std::vector<BackendRun> runs;
    for (std::size_t k = 0; k < backends.size(); ++k) {
      runs.push_back(trace(*backends[k], rays));
      closest_seconds[k] += runs.back().seconds_closest;
      closest_rays[k] += rays.size();
      progress.advance();
    }

    report += fmt::format("\n{} rays: {}\n", to_string(kind), rays.size());
    report += fmt::format("  {:<14} {:>10} {:>12} {:>12} {:>14} {:>12}\n", "backend", "hits", "closest Mr/s", "any Mr/s",
                          "any!=closest", "wrong u,v,ng");
    nlohmann::json j_kind = {{"rays", rays.size()}};
    std::string attribute_examples;
    for (std::size_t k = 0; k < backends.size(); ++k) {
      const BackendRun& r = runs[k];
      // Every backend's hits are judged on their own (not against the baseline): a right primitive at the right
      // t with swapped u and v or a flipped normal agrees with every other backend and still renders wrong.
      const AttributeTally attributes = rule_every_attribute(index, rays, r.closest);
      report += fmt::format("  {:<14} {:>10} {:>12.3f} {:>12.3f} {:>14} {:>12}\n", names[k], r.hits,
                            rate(rays.size(), r.seconds_closest) * 1e-6, rate(rays.size(), r.seconds_any) * 1e-6,
                            r.any_closest_disagreements, attributes.wrong);
      for (const auto& [i, why] : attributes.examples)
        attribute_examples += fmt::format("    wrong attributes of {}, ray {}: {}\n      bits: {}\n      {}: {}\n", names[k],
                                          i, why, hex_ray(rays[i]), names[k], describe_hit(r.closest[i]));
      total_genuine += r.any_closest_disagreements;
      total_wrong_attributes += attributes.wrong;
      wrong_attributes[k] += attributes.wrong;
      j_kind["backends"][names[k]] = {{"hits", r.hits},
                                      {"closest_rays_per_second", rate(rays.size(), r.seconds_closest)},
                                      {"any_rays_per_second", rate(rays.size(), r.seconds_any)},
                                      {"any_closest_disagreements", r.any_closest_disagreements},
                                      {"wrong_attributes", attributes.wrong}};
    }
    report += attribute_examples;
    report += fmt::format("  {:<14} {:>20} {:>7} {:>7} {:>8} {:>12} {:>22}\n", fmt::format("vs {}", names[0]),
                          "identical", "edge", "tie", "genuine", "max rel dt", "any-hit edge/genuine");
    j_kind["comparisons"] = nlohmann::json::array();
    std::vector<std::uint8_t> disputes(rays.size(), 0);
    for (std::size_t k = 1; k < backends.size(); ++k) {
      const PairComparison c = compare(index, rays, runs[0].closest, runs[k].closest, runs[0].occluded, runs[k].occluded);
      for (const std::size_t i : c.closest_disputes) disputes[i] |= kClosestDisputed;
      for (const std::size_t i : c.occlusion_disputes) disputes[i] |= kOcclusionDisputed;
      report += fmt::format("  {:<14} {:>10} ({:7.3f}%) {:>7} {:>7} {:>8} {:>12.3g} {:>22}\n", names[k], c.identical,
                            100.0 * c.identical_fraction(), c.edge, c.tie, c.genuine, c.max_rel_t_diff,
                            fmt::format("{}/{}", c.occlusion_edge, c.occlusion_genuine));
      for (const Mismatch& m : c.examples) {
        const Ray& ray = rays[m.ray_index];
        report += fmt::format("    genuine {} mismatch, ray {}: org ({:.9g}, {:.9g}, {:.9g}) dir ({:.9g}, {:.9g}, {:.9g}) "
                              "t [{:.9g}, {:.9g}]\n      {}: {}{}\n      {}: {}{}\n",
                              m.occlusion ? "any-hit" : "closest-hit", m.ray_index, ray.org.x, ray.org.y, ray.org.z,
                              ray.dir.x, ray.dir.y, ray.dir.z, ray.tmin, ray.tmax, names[0], describe_hit(m.a),
                              m.occlusion ? (m.occluded_a ? " (occluded)" : " (not occluded)") : "", names[k],
                              describe_hit(m.b), m.occlusion ? (m.occluded_b ? " (occluded)" : " (not occluded)") : "");
      }
      total_rays += c.rays;
      total_identical += c.identical;
      total_genuine += c.genuine + c.occlusion_genuine;
      j_kind["comparisons"].push_back({{"backend", names[k]},
                                       {"against", names[0]},
                                       {"rays", c.rays},
                                       {"identical", c.identical},
                                       {"identical_fraction", c.identical_fraction()},
                                       {"mismatches", {{"edge", c.edge}, {"tie", c.tie}, {"genuine", c.genuine}}},
                                       {"occlusion", {{"agree", c.occlusion_agree},
                                                      {"edge", c.occlusion_edge},
                                                      {"genuine", c.occlusion_genuine}}},
                                       {"max_rel_t_diff", c.max_rel_t_diff}});
    }
    if (arbiter) {
      std::vector<BackendAnswers> answers;
      for (std::size_t k = 0; k < backends.size(); ++k)
        answers.push_back({names[k], backends[k]->traits(), runs[k].closest, runs[k].occluded});
      const ArbitrationResult a =
          arbitrate(*arbiter, rays, answers, disputes, settings.arbiter_max_rays, kWrongExamples);
      arbiter_disputed += a.disputed_rays;
      arbiter_ruled_rays += a.ruled_rays;
      arbiter_seconds += a.seconds;
      if (a.capped()) capped_kinds.emplace_back(to_string(kind));
      if (a.disputed_rays == 0) {
        report += "  arbiter (exact): no disputed rays\n";
      } else {
        report += fmt::format("  arbiter (exact) on {} disputed rays{}, {:.2f} s:\n", a.disputed_rays,
                              a.capped() ? fmt::format(" (cap reached: the first {} ruled)", a.ruled_rays) : "",
                              a.seconds);
        report += fmt::format("  {:<14} {:>8} {:>8} {:>14}  {}\n", "backend", "ruled", "wrong", "max t rel err",
                              "wrong by reason");
      }
      nlohmann::json j_arbiter = nlohmann::json::object();
      for (std::size_t k = 0; k < backends.size(); ++k) {
        const ArbiterTally& t = a.backends[k];
        if (a.disputed_rays != 0)
          report += fmt::format("  {:<14} {:>8} {:>8} {:>14.3g}  {}\n", names[k], t.ruled, t.wrong, t.max_t_rel_error,
                                wrong_reasons_text(t));
        j_arbiter[names[k]] = {{"ruled", t.ruled}, {"wrong", t.wrong}, {"max_t_rel_error", t.max_t_rel_error},
                               {"reasons", reasons_json(t)}};
        accumulate(arbiter_totals[k], t, kWrongExamples);
      }
      for (std::size_t k = 0; k < backends.size(); ++k) {
        for (const WrongAnswer& w : a.backends[k].examples) {
          const Ray& ray = rays[w.ray_index];
          report += fmt::format(
              "    wrong {} answer of {}, ray {}: org ({:.9g}, {:.9g}, {:.9g}) dir ({:.9g}, {:.9g}, {:.9g}) t [{:.9g}, {:.9g}]\n"
              "      bits: {}\n      {}: {}\n      exact: {}\n      why: {}: {}\n",
              w.occlusion ? "any-hit" : "closest-hit", names[k], w.ray_index, ray.org.x, ray.org.y, ray.org.z, ray.dir.x,
              ray.dir.y, ray.dir.z, ray.tmin, ray.tmax, hex_ray(ray), names[k],
              w.occlusion ? (w.answered_occluded ? "occluded" : "not occluded") : describe_hit(w.answer),
              w.occlusion ? (w.ruling.exact_occluded ? "occluded" : "not occluded") : describe_hit(w.ruling.exact),
              arbiter::to_string(w.ruling.reason), w.ruling.detail);
        }
      }
      j_kind["arbiter"] = j_arbiter;
      j_kind["arbiter_rays"] = {{"disputed", a.disputed_rays}, {"ruled", a.ruled_rays}, {"seconds", a.seconds}};
    }
    j_kinds[std::string(to_string(kind))] = j_kind;
  }
  progress.finish();

  const double identical_fraction =
      total_rays ? static_cast<double>(total_identical) / static_cast<double>(total_rays) : 1.0;
  report += "\nclosest-hit rays per second on one thread:";
  nlohmann::json j_rates = nlohmann::json::object();
  for (std::size_t k = 0; k < backends.size(); ++k) {
    const double r = rate(closest_rays[k], closest_seconds[k]);
    report += fmt::format("  {} {:.3f} M", names[k], r * 1e-6);
    j_rates[names[k]] = r;
  }
  std::size_t arbiter_wrong = 0;
  nlohmann::json j_arbiter = nlohmann::json::object();
  if (arbiter) {
    report += fmt::format("\narbiter (exact): {} disputed rays, {} ruled, {:.2f} s{}\n", arbiter_disputed,
                          arbiter_ruled_rays, arbiter_seconds,
                          capped_kinds.empty() ? "" : fmt::format(" (cap of {} rays per kind reached for {})",
                                                                  settings.arbiter_max_rays, fmt::join(capped_kinds, ", ")));
    for (std::size_t k = 0; k < backends.size(); ++k) {
      const ArbiterTally& t = arbiter_totals[k];
      report += fmt::format("  {:<14} ruled {:>8}  wrong {:>8}  max t rel err {:>10.3g}  {}\n", names[k], t.ruled,
                            t.wrong, t.max_t_rel_error, wrong_reasons_text(t));
      j_arbiter[names[k]] = tally_json(t);
      arbiter_wrong += t.wrong;
    }
  }
  const bool passed = total_genuine == 0 && total_wrong_attributes == 0 && (!settings.strict || arbiter_wrong == 0);
  const std::string arbiter_clause =
      arbiter_wrong == 0 ? std::string()
                         : fmt::format(", {} answers the arbiter ruled wrong{}", arbiter_wrong,
                                       settings.strict ? "" : " (reported; --strict fails on them)");
  report += fmt::format("\nverdict: {} ({} genuine mismatches, {} closest hits with wrong u, v or ng, {:.4f}% identical{})\n",
                        passed ? "PASS" : "FAIL", total_genuine, total_wrong_attributes, 100.0 * identical_fraction,
                        arbiter_clause);
  nlohmann::json j_wrong_attributes = nlohmann::json::object();
  for (std::size_t k = 0; k < backends.size(); ++k) j_wrong_attributes[names[k]] = wrong_attributes[k];

  CrosscheckReport out;
  out.text = std::move(report);
  out.genuine_mismatches = total_genuine;
  out.wrong_attributes = total_wrong_attributes;
  out.arbiter_wrong = arbiter_wrong;
  out.strict = settings.strict;
  out.json = {{"scene", scene.source.string()},
              {"seed", settings.seed},
              {"rays_per_kind", settings.rays_per_kind},
              {"backends", names},
              {"baseline", names[0]},
              {"build", j_build},
              {"kinds", j_kinds},
              {"rays_per_second", j_rates},
              {"genuine_mismatches", total_genuine},
              {"wrong_attributes", j_wrong_attributes},
              {"identical_fraction", identical_fraction},
              {"tolerances", {{"rel_t", kRelT}, {"abs_world", kAbsWorld}, {"grazing_cos", kGrazingCos}}},
              {"strict", settings.strict},
              {"verdict", passed ? "pass" : "fail"}};
  if (arbiter) {
    out.json["arbiter"] = j_arbiter;
    out.json["arbiter_settings"] = {{"enabled", true},
                                    {"max_rays_per_kind", settings.arbiter_max_rays},
                                    {"disputed_rays", arbiter_disputed},
                                    {"ruled_rays", arbiter_ruled_rays},
                                    {"capped_kinds", capped_kinds},
                                    {"seconds", arbiter_seconds},
                                    {"tolerances", {{"world", arbiter::kWorld}, {"rel_t", arbiter::kRelT}}}};
  } else {
    out.json["arbiter_settings"] = {{"enabled", false}};
  }
  return out;
}

}  // namespace twinray::crosscheck
