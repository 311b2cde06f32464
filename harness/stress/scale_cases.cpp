// Scale cases: the same scene at 1e-6 and 1e6 of its size, and spheres at extreme radius-to-distance
// ratios (huge spheres with nearby origins, tiny far ones, origins inside). Sources: docs/stress.md.

#include "harness/crosscheck/hit_comparison.h"
#include "harness/stress/stress_case.h"
#include "harness/stress/stress_support.h"
#include "core/geometry/ray.h"
#include "core/sampling/rng.h"
#include "core/sampling/warp.h"
#include "core/scene/procedural.h"

#include <fmt/core.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <utility>
#include <vector>

namespace twinray::stress {

namespace {

SceneGeometry scaled_geometry(SceneGeometry g, float s) {
  for (TriangleMesh& m : g.meshes)
    for (glm::vec3& p : m.positions) p *= s;
  for (Sphere& sp : g.spheres) {
    sp.center *= s;
    sp.radius *= s;
  }
  return g;
}

// Intersection must not care about units: the scene and its rays scaled by s (not a power of two, so
// every coordinate is rounded anew) must hit the same primitives at the same relative t. Disagreements on
// an edge or silhouette (the crosscheck classifier's "edge") are allowed, since rounding moved the edge.
Outcome scale_invariance(const std::string& backend_name, const StressOptions& options) {
  Outcome out;
  const SceneGeometry base = mixed_spheres_and_triangles(60, 6000, 9);
  const auto base_backend = build_backend(backend_name, base);
  const crosscheck::GeometryIndex base_index(base);
  const std::size_t n = scaled(20000, options, 200);
  Rng rng(31, 0);
  std::vector<Ray> rays(n);
  std::vector<Hit> base_hits(n);
  for (std::size_t i = 0; i < n; ++i) {
    rays[i].org = 2.5f * sample_uniform_sphere({rng.next_float(), rng.next_float()});
    rays[i].dir = glm::normalize(sample_uniform_sphere({rng.next_float(), rng.next_float()}) - rays[i].org);
    base_backend->intersect(rays[i], base_hits[i]);
  }
  std::size_t genuine_total = 0;
  std::string figures;
  for (const float s : {1e-6f, 1e6f}) {
    const SceneGeometry geometry = scaled_geometry(base, s);
    const auto backend = build_backend(backend_name, geometry);
    const crosscheck::GeometryIndex index(geometry);
    std::size_t identical = 0, edge = 0, genuine = 0;
    double max_rel = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      Ray ray = rays[i];
      ray.org *= s;  // the direction stays unit: t scales by s
      Hit hit;
      backend->intersect(ray, hit);
      const Hit& h0 = base_hits[i];
      bool same = h0.found() == hit.found();
      if (same && h0.found()) {
        const double rel = relative_difference(h0.t, static_cast<double>(hit.t) / s);
        same = h0.geom_id == hit.geom_id && h0.prim_id == hit.prim_id && rel <= crosscheck::kRelT;
        if (h0.geom_id == hit.geom_id && h0.prim_id == hit.prim_id) max_rel = std::max(max_rel, rel);
      }
      if (same) {
        ++identical;
      } else if (crosscheck::hit_is_ambiguous(base_index, rays[i], h0) ||
                 crosscheck::hit_is_ambiguous(index, ray, hit)) {
        ++edge;
      } else {
        ++genuine;
      }
    }
    genuine_total += genuine;
    figures += fmt::format(" x{:g}: {} identical, {} edge, {} genuine, max rel dt {:.2g};", s, identical, edge,
                           genuine, max_rel);
    out.json[fmt::format("{:g}", s)] = {{"rays", n}, {"identical", identical}, {"edge", edge}, {"genuine", genuine},
                                        {"max_rel_t_diff", max_rel}};
  }
  out.status = genuine_total == 0 ? Status::Pass : Status::Fail;
  out.figures = fmt::format("{} rays;{}", n, figures);
  out.figures.pop_back();
  set_requirement(out, backend_name, true, "");
  return out;
}

// Reference roots in long double, with the same closest-approach form that keeps tiny far spheres
// accurate (the textbook discriminant cancels ~66 bits there, more than long double has).
struct ReferenceRoots {
  bool hit = false;
  long double t0 = 0, t1 = 0;
  long double closest_approach = 0;  // distance from the centre to the line
};
ReferenceRoots reference_roots(const Ray& ray, const Sphere& s) {
  using L = long double;
  const L dx = ray.dir.x, dy = ray.dir.y, dz = ray.dir.z;
  const L fx = L(ray.org.x) - L(s.center.x), fy = L(ray.org.y) - L(s.center.y), fz = L(ray.org.z) - L(s.center.z);
  const L a = dx * dx + dy * dy + dz * dz;
  const L b = fx * dx + fy * dy + fz * dz;
  const L k = b / a;
  const L lx = fx - k * dx, ly = fy - k * dy, lz = fz - k * dz;
  const L l2 = lx * lx + ly * ly + lz * lz;
  const L r = s.radius;
  ReferenceRoots out;
  out.closest_approach = std::sqrt(l2);
  const L disc = a * (r * r - l2);
  if (disc < 0) return out;
  const L q = -(b + (b >= 0 ? 1 : -1) * std::sqrt(disc));
  const L flen = std::sqrt(fx * fx + fy * fy + fz * fz);
  const L c = (flen - r) * (flen + r);
  L t0 = c / q, t1 = q / a;
  if (t0 > t1) std::swap(t0, t1);
  out.hit = true;
  out.t0 = t0;
  out.t1 = t1;
  return out;
}

// Three sphere regimes, each against a long-double reference. Rays whose line passes within 1e-3 r of the
// silhouette are not judged (there hit or miss depends on the last bit of the inputs). Otherwise: the
// backend must hit exactly when the reference does, at a t within 1e-4 relative (kRelT) of it.
Outcome sphere_precision(const std::string& backend_name, const StressOptions& options) {
  Outcome out;
  struct Regime {
    const char* name;
    Sphere sphere;
    float origin_distance_min, origin_distance_max;  // from the surface (negative: inside)
  };
  const Regime regimes[] = {
      {"huge r=1e5, origins 1e-3..10 above", {0, {0.0f, -1e5f, 0.0f}, 1e5f}, 1e-3f, 10.0f},
      {"tiny r=1e-2 at 1e4", {0, {1e4f, 2e3f, -3e3f}, 1e-2f}, 1e4f, 1e4f},
      {"inside r=1", {0, {0.5f, 0.25f, -0.125f}, 1.0f}, -1.0f, -1e-3f},
      {"inside huge r=1e5", {0, {0.0f, -1e5f, 0.0f}, 1e5f}, -10.0f, -1e-3f},
      {"inside tiny r=1e-2 at 1e4", {0, {1e4f, 2e3f, -3e3f}, 1e-2f}, -1e-2f, -1e-5f},
  };
  const std::size_t n = scaled(5000, options, 100);
  std::size_t total_wrong = 0;
  std::string figures;
  int regime_index = 0;
  for (const Regime& reg : regimes) {
    SceneGeometry geometry;
    geometry.spheres.push_back(reg.sphere);
    const auto backend = build_backend(backend_name, geometry);
    Rng rng(41, static_cast<std::uint64_t>(regime_index++));
    std::size_t judged = 0, wrong = 0, hits = 0;
    double max_rel = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Sphere& s = reg.sphere;
      // An origin at the requested signed distance from the surface, above the sphere's top for the huge
      // one (where "nearby" matters), anywhere around it otherwise.
      const glm::vec3 radial = s.radius > 1e4f ? glm::normalize(glm::vec3(1e-4f * (rng.next_float() - 0.5f), 1.0f,
                                                                           1e-4f * (rng.next_float() - 0.5f)))
                                               : sample_uniform_sphere({rng.next_float(), rng.next_float()});
      const float frac = rng.next_float();
      const float dist = reg.origin_distance_min + frac * (reg.origin_distance_max - reg.origin_distance_min);
      Ray ray;
      const glm::dvec3 o = glm::dvec3(s.center) + (static_cast<double>(s.radius) + dist) * glm::dvec3(radial);
      ray.org = glm::vec3(o);
      if (reg.origin_distance_min > 1e3f) {
        // Tiny far sphere: aim at the centre, offset sideways by up to 2 r (half of them miss).
        const glm::dvec3 side = glm::dvec3(sample_uniform_sphere({rng.next_float(), rng.next_float()}));
        const glm::dvec3 aim = glm::dvec3(s.center) + 2.0 * s.radius * rng.next_double() * side;
        ray.dir = glm::vec3(glm::normalize(aim - glm::dvec3(ray.org)));
      } else {
        ray.dir = sample_uniform_sphere({rng.next_float(), rng.next_float()});
      }
      const ReferenceRoots ref = reference_roots(ray, s);
      if (std::fabs(static_cast<double>(ref.closest_approach) - s.radius) < 1e-3 * s.radius) continue;
      // The reference's first root at or after tmin = 0.
      bool expect = false;
      long double t_ref = 0;
      if (ref.hit) {
        if (ref.t0 >= 0) { expect = true; t_ref = ref.t0; }
        else if (ref.t1 >= 0) { expect = true; t_ref = ref.t1; }
      }
      Hit hit;
      const bool found = backend->intersect(ray, hit);
      ++judged;
      hits += found ? 1 : 0;
      bool ok = found == expect;
      if (ok && found) {
        const double rel = relative_difference(static_cast<double>(t_ref), hit.t);
        max_rel = std::max(max_rel, rel);
        ok = rel <= crosscheck::kRelT;
      }
      wrong += ok ? 0 : 1;
    }
    total_wrong += wrong;
    figures += fmt::format(" {}: {}/{} wrong (max rel dt {:.2g});", reg.name, wrong, judged, max_rel);
    out.json[reg.name] = {{"judged", judged}, {"hits", hits}, {"wrong", wrong}, {"max_rel_t_diff", max_rel}};
  }
  out.status = total_wrong == 0 ? Status::Pass : Status::Fail;
  out.figures = figures.substr(1, figures.size() - 2);
  set_requirement(out, backend_name, true, "");
  return out;
}

}  // namespace

void add_scale_cases(std::vector<StressCase>& cases) {
  cases.push_back({"scale-invariance", "scale",
                   "the same scene scaled by 1e-6 and 1e6: same primitives, same relative t", scale_invariance});
  cases.push_back({"sphere-precision", "scale",
                   "huge spheres (r 1e5) with nearby origins, tiny far spheres, origins inside spheres",
                   sphere_precision});
}

}  // namespace twinray::stress
