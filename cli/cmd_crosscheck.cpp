// twinray crosscheck: the same rays through several backends, and a verdict on every disagreement.

#include "backends/registry.h"
#include "cli/commands.h"
#include "cli/crosscheck/hit_comparison.h"
#include "cli/crosscheck/ray_generation.h"
#include "cli/crosscheck/ray_kinds.h"
#include "core/scene/scene_loader.h"
#include "core/util/atomic_file.h"
#include "core/util/fp_mode.h"
#include "core/util/progress.h"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <memory>
#include <stdexcept>

namespace twinray::cli {

namespace {

struct CrosscheckOptions {
  std::string scene;
  std::string backends = "bvh,embree";
  // Signed on purpose: CLI11 would wrap "-5" into a huge unsigned count.
  std::int64_t rays = 100000;
  std::string kinds = "camera,uniform,diffuse,shadow";
  std::uint64_t seed = 1;
  std::string json;
};

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

double rate(std::size_t n, double seconds) { return seconds > 0.0 ? static_cast<double>(n) / seconds : 0.0; }

std::string describe_hit(const Hit& h) {
  if (!h.found()) return "miss";
  return fmt::format("geom {} prim {} t={:.9g} uv=({:.6g},{:.6g})", h.geom_id, h.prim_id, h.t, h.u, h.v);
}

int run_crosscheck(const CrosscheckOptions& opt) {
  std::vector<std::string> names;
  std::vector<crosscheck::RayKind> kinds;
  try {
    names = parse_backend_list(opt.backends);
    kinds = crosscheck::parse_ray_kinds(opt.kinds);
  } catch (const std::invalid_argument& e) {
    return report_bad_input("crosscheck", e.what());
  }
  if (names.size() < 2) {
    return report_bad_input("crosscheck", "--backends needs at least two backends to compare");
  }
  // Each ray costs 32 bytes plus a 40-byte hit and an any-hit flag per backend: 10M rays stay near 1 GB.
  constexpr std::int64_t kMaxRays = 10'000'000;
  if (opt.rays < 1 || opt.rays > kMaxRays) {
    return report_bad_input("crosscheck", fmt::format("--rays must be between 1 and {}, got {}", kMaxRays, opt.rays));
  }

  const ScopedFlushDenormals ftz;
  const Scene scene = load_scene(opt.scene);
  const crosscheck::GeometryIndex index(scene.geometry);

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
    j_build[name] = {{"build_seconds", bs.build_seconds}, {"memory_bytes", bs.memory_bytes}};
  }

  Progress progress("crosscheck", kinds.size() * backends.size());
  std::size_t total_rays = 0, total_identical = 0, total_genuine = 0;
  std::vector<double> closest_seconds(backends.size(), 0.0);
  std::vector<std::size_t> closest_rays(backends.size(), 0);
  nlohmann::json j_kinds = nlohmann::json::object();
  std::string report;

  for (const crosscheck::RayKind kind : kinds) {
    const std::vector<Ray> rays = crosscheck::generate_rays(kind, scene, *backends.front(), static_cast<std::size_t>(opt.rays), opt.seed);
    std::vector<BackendRun> runs;
    for (std::size_t k = 0; k < backends.size(); ++k) {
      runs.push_back(trace(*backends[k], rays));
      closest_seconds[k] += runs.back().seconds_closest;
      closest_rays[k] += rays.size();
      progress.advance();
    }

    report += fmt::format("\n{} rays: {}\n", crosscheck::to_string(kind), rays.size());
    report += fmt::format("  {:<14} {:>10} {:>12} {:>12} {:>14}\n", "backend", "hits", "closest Mr/s", "any Mr/s",
                          "any!=closest");
    nlohmann::json j_kind = {{"rays", rays.size()}};
    for (std::size_t k = 0; k < backends.size(); ++k) {
      const BackendRun& r = runs[k];
      report += fmt::format("  {:<14} {:>10} {:>12.3f} {:>12.3f} {:>14}\n", names[k], r.hits,
                            rate(rays.size(), r.seconds_closest) * 1e-6, rate(rays.size(), r.seconds_any) * 1e-6,
                            r.any_closest_disagreements);
      total_genuine += r.any_closest_disagreements;
      j_kind["backends"][names[k]] = {{"hits", r.hits},
                                      {"closest_rays_per_second", rate(rays.size(), r.seconds_closest)},
                                      {"any_rays_per_second", rate(rays.size(), r.seconds_any)},
                                      {"any_closest_disagreements", r.any_closest_disagreements}};
    }
    report += fmt::format("  {:<14} {:>20} {:>7} {:>7} {:>8} {:>12} {:>22}\n", fmt::format("vs {}", names[0]),
                          "identical", "edge", "tie", "genuine", "max rel dt", "any-hit edge/genuine");
    j_kind["comparisons"] = nlohmann::json::array();
    for (std::size_t k = 1; k < backends.size(); ++k) {
      const crosscheck::PairComparison c =
          crosscheck::compare(index, rays, runs[0].closest, runs[k].closest, runs[0].occluded, runs[k].occluded);
      report += fmt::format("  {:<14} {:>10} ({:7.3f}%) {:>7} {:>7} {:>8} {:>12.3g} {:>22}\n", names[k], c.identical,
                            100.0 * c.identical_fraction(), c.edge, c.tie, c.genuine, c.max_rel_t_diff,
                            fmt::format("{}/{}", c.occlusion_edge, c.occlusion_genuine));
      for (const crosscheck::Mismatch& m : c.examples) {
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
    j_kinds[std::string(crosscheck::to_string(kind))] = j_kind;
  }
  progress.finish();

  const double identical_fraction =
      total_rays ? static_cast<double>(total_identical) / static_cast<double>(total_rays) : 1.0;
  fmt::print("{}", report);
  fmt::print("\nclosest-hit rays per second on one thread:");
  nlohmann::json j_rates = nlohmann::json::object();
  for (std::size_t k = 0; k < backends.size(); ++k) {
    const double r = rate(closest_rays[k], closest_seconds[k]);
    fmt::print("  {} {:.3f} M", names[k], r * 1e-6);
    j_rates[names[k]] = r;
  }
  fmt::print("\nverdict: {} ({} genuine mismatches, {:.4f}% identical)\n", total_genuine == 0 ? "PASS" : "FAIL",
             total_genuine, 100.0 * identical_fraction);

  if (!opt.json.empty()) {
    nlohmann::json j = {{"scene", scene.source.string()},
                        {"seed", opt.seed},
                        {"rays_per_kind", opt.rays},
                        {"backends", names},
                        {"baseline", names[0]},
                        {"build", j_build},
                        {"kinds", j_kinds},
                        {"rays_per_second", j_rates},
                        {"genuine_mismatches", total_genuine},
                        {"identical_fraction", identical_fraction},
                        {"tolerances", {{"rel_t", crosscheck::kRelT}, {"abs_world", crosscheck::kAbsWorld},
                                        {"grazing_cos", crosscheck::kGrazingCos}}},
                        {"verdict", total_genuine == 0 ? "pass" : "fail"}};
    write_file_atomically(opt.json, j.dump(2) + "\n");
  }
  return total_genuine == 0 ? kExitOk : kExitCheckFailed;
}

}  // namespace

void add_crosscheck_command(CLI::App& app, CommandRunner& run) {
  auto opt = std::make_shared<CrosscheckOptions>();
  CLI::App* cmd = app.add_subcommand(
      "crosscheck",
      "Trace the same rays through several backends and classify every disagreement.\n"
      "Exit code: 0 no genuine mismatch, 1 at least one genuine mismatch, 2 bad input.");
  cmd->add_option("scene", opt->scene, "Scene (.json) or bare mesh (.obj, .ply)")->required();
  cmd->add_option("--backends", opt->backends,
                  "Comma-separated backends; the first is the baseline the others are compared with "
                  "(bvh, embree, embree-fast, brute, plugin:PATH)")
      ->capture_default_str();
  cmd->add_option("--rays", opt->rays, "Rays per kind")->capture_default_str();
  cmd->add_option("--kinds", opt->kinds, "Ray kinds: camera, uniform, diffuse, shadow")->capture_default_str();
  cmd->add_option("--seed", opt->seed, "Random seed for ray generation")->capture_default_str();
  cmd->add_option("--json", opt->json, "Write the figures as JSON to this file");
  cmd->callback([opt, &run] { run = [opt] { return run_crosscheck(*opt); }; });
}

}  // namespace twinray::cli
