#include "harness/trace/trace_run.h"

#include "backends/bvh/bvh_backend.h"
#include "backends/registry.h"
#include "core/util/float_ulps.h"
#include "core/util/fp_mode.h"
#include "core/util/input_error.h"
#include "core/util/text_safety.h"
#include "harness/crosscheck/hit_comparison.h"
#include "harness/scenes/named_scene.h"
#include "core/geometry/ray_text.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>

namespace twinray::trace {

namespace {

struct Answer {
  std::string name;
  BackendTraits traits;
  std::string error;  // non-empty: the backend failed to build or answer
  Hit hit;
  bool occluded = false;
  QueryStats closest_stats, any_stats;
  std::optional<std::vector<BvhVisit>> closest_visits, any_visits;  // bvh only
};

// Where the ray enters and leaves a node's box, in double (display only; the traversal has its own test).
std::pair<double, double> box_span(const Ray& ray, const BvhNode& node) {
  double t0 = -INFINITY, t1 = INFINITY;
  for (int a = 0; a < 3; ++a) {
    const double o = ray.org[a], d = ray.dir[a];
    if (d == 0.0) {
      if (o < node.lo[a] || o > node.hi[a]) return {INFINITY, -INFINITY};
      continue;
    }
    double n = (node.lo[a] - o) / d, f = (node.hi[a] - o) / d;
    if (n > f) std::swap(n, f);
    t0 = std::max(t0, n);
    t1 = std::min(t1, f);
  }
  return {t0, t1};
}

std::string describe_hit(const Hit& h) {
  if (!h.found()) return "miss";
  return fmt::format("geom {} prim {}  t {:.9g} ({})  u {:.9g}  v {:.9g}  ng ({:.6g}, {:.6g}, {:.6g})", h.geom_id,
                     h.prim_id, h.t, hex_float(h.t), h.u, h.v, h.ng.x, h.ng.y, h.ng.z);
}

nlohmann::json hit_json(const Hit& h) {
  if (!h.found()) return {{"hit", false}};
  return {{"hit", true},        {"t", h.t},           {"t_hex", hex_float(h.t)}, {"u", h.u},
          {"u_hex", hex_float(h.u)}, {"v", h.v},      {"v_hex", hex_float(h.v)}, {"geom_id", h.geom_id},
          {"prim_id", h.prim_id}, {"ng", {h.ng.x, h.ng.y, h.ng.z}}};
}

nlohmann::json stats_json(const QueryStats& s) {
  return {{"nodes_visited", s.nodes_visited}, {"primitives_tested", s.primitives_tested}};
}

nlohmann::json float_json(float f) { return std::isfinite(f) ? nlohmann::json(f) : nlohmann::json(hex_float(f)); }

std::string visit_lines(const std::vector<BvhVisit>& visits, const BvhBackend& bvh, const Ray& ray, nlohmann::json& out) {
  std::string text;
  out = nlohmann::json::array();
  const auto nodes = bvh.nodes();
  for (std::size_t k = 0; k < visits.size(); ++k) {
    const BvhNode& node = nodes[visits[k].node];
    const auto [t0, t1] = box_span(ray, node);
    const std::string kind = node.is_leaf() ? fmt::format("leaf, {} {}", node.prim_count(),
                                                          node.is_sphere_leaf() ? "spheres" : "triangles")
                                            : fmt::format("interior, children {} and {}", visits[k].node + 1,
                                                          node.second_child());
    text += fmt::format("      {:>4}. node {:<8} {:<34} box t [{:.6g}, {:.6g}]  searching to {:.6g}\n", k + 1,
                        visits[k].node, kind, t0, t1, visits[k].tmax);
    out.push_back({{"node", visits[k].node},
                   {"leaf", node.is_leaf()},
                   {"primitives", node.is_leaf() ? node.prim_count() : 0u},
                   {"box_entry", std::isfinite(t0) ? nlohmann::json(t0) : nlohmann::json(nullptr)},
                   {"box_exit", std::isfinite(t1) ? nlohmann::json(t1) : nlohmann::json(nullptr)},
                   {"tmax", float_json(visits[k].tmax)}});
  }
  return text;
}

}  // namespace

TraceReport run_trace(const TraceSettings& settings) {
  if (settings.backends.empty()) throw std::invalid_argument("--backends needs at least one backend");
  const ScopedFlushDenormals ftz;  // the mode every other command queries backends in
  const Scene scene = load_named_scene(settings.scene);
  const Ray& ray = settings.ray;

  TraceReport report;
  std::string& out = report.text;
  out += fmt::format("scene {}: {} triangles, {} spheres\n", settings.scene, scene.geometry.triangle_count(),
                     scene.geometry.sphere_count());
  out += fmt::format("ray   org ({:.9g}, {:.9g}, {:.9g})  dir ({:.9g}, {:.9g}, {:.9g})  t [{:.9g}, {:.9g}]\n", ray.org.x,
                     ray.org.y, ray.org.z, ray.dir.x, ray.dir.y, ray.dir.z, ray.tmin, ray.tmax);
  out += fmt::format("      --ray '{}'\n", format_ray_hex(ray));
  if (!is_valid_ray(ray))
    out += "      not a valid ray (core/geometry/ray.h): every backend reports a miss\n";

  std::vector<std::unique_ptr<Backend>> backends;
  std::vector<Answer> answers;
  for (const std::string& name : settings.backends) {
    Answer a;
    a.name = name;
    std::unique_ptr<Backend> backend = make_backend(name);  // InputError (a bad plugin path) is bad input
    try {
      a.traits = backend->traits();
      backend->build(scene.geometry);
      if (const auto* bvh = dynamic_cast<const BvhBackend*>(backend.get()); bvh != nullptr && settings.visits) {
        a.closest_visits.emplace();
        a.any_visits.emplace();
        bvh->intersect_traced(ray, a.hit, *a.closest_visits, &a.closest_stats);
        a.occluded = bvh->occluded_traced(ray, *a.any_visits, &a.any_stats);
      } else {
        backend->intersect(ray, a.hit, &a.closest_stats);
        a.occluded = backend->occluded(ray, &a.any_stats);
      }
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      // A backend that fails (a plugin's crash, timeout or contract violation) is an answer too, in one safe
      // line: the message may carry the plugin's own words.
      a.error = one_line(e.what());
      report.all_answered = false;
    }
    answers.push_back(std::move(a));
    backends.push_back(std::move(backend));
  }

  const crosscheck::GeometryIndex index(scene.geometry);
  nlohmann::json j_backends = nlohmann::json::array();
  for (std::size_t k = 0; k < answers.size(); ++k) {
    const Answer& a = answers[k];
    nlohmann::json j = {{"name", a.name}};
    out += fmt::format("\n{}\n", a.name);
    if (!a.error.empty()) {
      out += fmt::format("  failed   {}\n", a.error);
      j["error"] = a.error;
      j_backends.push_back(j);
      continue;
    }
    out += fmt::format("  closest  {}\n", describe_hit(a.hit));
    out += fmt::format("  any-hit  {}\n", a.occluded ? "occluded" : "not occluded");
    j["closest"] = hit_json(a.hit);
    j["occluded"] = a.occluded;
    j["counts_traversal"] = a.traits.counts_traversal;
    if (a.traits.counts_traversal) {
      out += fmt::format("  work     closest: {} nodes, {} primitives; any-hit: {} nodes, {} primitives\n",
                         a.closest_stats.nodes_visited, a.closest_stats.primitives_tested, a.any_stats.nodes_visited,
                         a.any_stats.primitives_tested);
      j["closest_stats"] = stats_json(a.closest_stats);
      j["any_stats"] = stats_json(a.any_stats);
    }
    if (a.closest_visits) {
      const auto& bvh = dynamic_cast<const BvhBackend&>(*backends[k]);
      nlohmann::json jc, ja;
      out += fmt::format("    nodes entered by the closest-hit query ({}):\n", a.closest_visits->size());
      out += visit_lines(*a.closest_visits, bvh, ray, jc);
      out += fmt::format("    nodes entered by the any-hit query ({}):\n", a.any_visits->size());
      out += visit_lines(*a.any_visits, bvh, ray, ja);
      j["visits"] = {{"closest", jc}, {"any", ja}};
    }
    if (k > 0 && answers[0].error.empty()) {
      const Answer& base = answers[0];
      const std::uint8_t oa = base.occluded ? 1 : 0, ob = a.occluded ? 1 : 0;
      const crosscheck::PairComparison c = crosscheck::compare(index, std::span<const Ray>(&ray, 1),
                                                               std::span<const Hit>(&base.hit, 1),
                                                               std::span<const Hit>(&a.hit, 1),
                                                               std::span<const std::uint8_t>(&oa, 1),
                                                               std::span<const std::uint8_t>(&ob, 1));
      const std::string closest = c.identical ? "identical" : c.edge ? "edge" : c.tie ? "tie" : "genuine";
      const std::string any = c.occlusion_agree ? "agree" : c.occlusion_edge ? "edge" : "genuine";
      // Hits on the same primitive: how far apart their t are, in floats. "identical" allows a tolerance
      // (hit_comparison.h); against `exact` this says whether a backend's t is the correctly rounded one.
      std::string t_note;
      const bool same_primitive = base.hit.found() && a.hit.found() && base.hit.geom_id == a.hit.geom_id &&
                                  base.hit.prim_id == a.hit.prim_id && std::isfinite(base.hit.t) && std::isfinite(a.hit.t);
      if (same_primitive) {
        const std::int64_t ulps = float_ulp_distance(a.hit.t, base.hit.t);
        j["t_ulps_from_reference"] = ulps;
        t_note = ulps == 0 ? fmt::format(" (the same t as {})", base.name)
                           : fmt::format(" (t {} ulp{} from {}'s)", ulps, ulps == 1 ? "" : "s", base.name);
      }
      out += fmt::format("  vs {}: closest hit {}{}, any-hit {}\n", base.name, closest, t_note, any);
      j["against"] = base.name;
      j["closest_comparison"] = closest;
      j["any_comparison"] = any;
      if (closest != "identical" || any != "agree") report.agree = false;
    }
    j_backends.push_back(j);
  }

  report.json = {{"scene", settings.scene},
                 {"ray",
                  {{"org", {ray.org.x, ray.org.y, ray.org.z}},
                   {"dir", {ray.dir.x, ray.dir.y, ray.dir.z}},
                   {"tmin", float_json(ray.tmin)},
                   {"tmax", float_json(ray.tmax)},
                   {"hex", format_ray_hex(ray)},
                   {"valid", is_valid_ray(ray)}}},
                 {"backends", j_backends},
                 {"all_answered", report.all_answered},
                 {"agree", report.agree}};
  return report;
}

}  // namespace twinray::trace
