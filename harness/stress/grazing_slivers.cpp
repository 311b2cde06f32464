// The grazing-slivers case: long thin triangles hit at grazing angles, every answer ruled by the arbiter
// against the exact backend. docs/stress.md says what it checks and why it is hard.

#include "harness/arbiter/arbiter.h"
#include "harness/stress/stress_case.h"
#include "harness/stress/stress_support.h"
#include "core/sampling/rng.h"
#include "core/scene/geometry_cleanup.h"

#include <fmt/core.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <map>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace twinray::stress {

namespace {

constexpr double kAspects[] = {1e2, 1e3, 1e4, 1e5};
constexpr double kMinAngleDegrees = 1e-4, kMaxAngleDegrees = 1.0;

// Log-uniform in [lo, hi].
double log_uniform(Rng& rng, double lo, double hi) {
  return lo * std::pow(hi / lo, static_cast<double>(rng.next_float()));
}

double grazing_angle(Rng& rng) {
  return log_uniform(rng, kMinAngleDegrees, kMaxAngleDegrees) * std::numbers::pi / 180.0;
}

// A unit vector perpendicular to n, at a random angle around it.
glm::dvec3 random_tangent(Rng& rng, const glm::dvec3& n) {
  const glm::dvec3 helper = std::fabs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  const glm::dvec3 a = glm::normalize(glm::cross(n, helper)), b = glm::cross(n, a);
  const double phi = 2.0 * std::numbers::pi * static_cast<double>(rng.next_float());
  return std::cos(phi) * a + std::sin(phi) * b;
}

glm::vec3 to_float(const glm::dvec3& v) { return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)}; }

struct Scenario {
  std::string name;
  SceneGeometry geometry;
  std::vector<Ray> rays;
};

// Open slivers: per aspect ratio, triangles of long edge `size` and height size/aspect in random orientations
// around `center`, each shot through a random interior point at a random grazing angle, from either side.
Scenario open_slivers(const glm::dvec3& center, double size, std::size_t rays_per_sliver, std::uint64_t seed) {
  Scenario s;
  s.name = "open";
  Rng rng(seed, 1);
  TriangleMesh mesh;
  std::vector<std::array<glm::dvec3, 3>> triangles;
  for (const double aspect : kAspects) {
    for (int k = 0; k < 8; ++k) {
      const glm::dvec3 n = glm::normalize(glm::dvec3(2.0 * rng.next_float() - 1.0, 2.0 * rng.next_float() - 1.0,
                                                     2.0 * rng.next_float() - 1.0 + 1e-3));
      const glm::dvec3 along = random_tangent(rng, n), across = glm::cross(n, along);
      const glm::dvec3 base =
          center + 2.0 * size * glm::dvec3(rng.next_float() - 0.5, rng.next_float() - 0.5, rng.next_float() - 0.5);
      const double apex = static_cast<double>(rng.next_float());  // where the short apex sits along the long edge
      const std::array<glm::dvec3, 3> tri = {base, base + size * along, base + size * (apex * along + across / aspect)};
      const auto first = static_cast<std::uint32_t>(mesh.positions.size());
      for (const glm::dvec3& p : tri) mesh.positions.push_back(to_float(p));
      mesh.indices.push_back({first, first + 1, first + 2});
      triangles.push_back(tri);
    }
  }
  ensure_vertex_padding(mesh.positions);
  s.geometry.meshes.push_back(std::move(mesh));
  for (const auto& tri : triangles) {
    const glm::dvec3 e1 = tri[1] - tri[0], e2 = tri[2] - tri[0];
    const glm::dvec3 n = glm::normalize(glm::cross(e1, e2));
    for (std::size_t i = 0; i < rays_per_sliver; ++i) {
      double u = rng.next_float(), v = rng.next_float();
      if (u + v > 1.0) {
        u = 1.0 - u;
        v = 1.0 - v;
      }
      const glm::dvec3 target = tri[0] + u * e1 + v * e2;
      const double theta = grazing_angle(rng);
      const double side = rng.next_below(2) == 0 ? 1.0 : -1.0;
      const glm::dvec3 d = std::cos(theta) * random_tangent(rng, n) - side * std::sin(theta) * n;
      Ray ray;
      ray.org = to_float(target - size * (0.1 + 1.9 * rng.next_float()) * d);
      ray.dir = to_float(d);
      s.rays.push_back(ray);
    }
  }
  return s;
}

// A rotation taking the box's axes to three random orthonormal directions: the faces must not be axis
// aligned, where every intersector computes t exactly.
struct Frame3 {
  glm::dvec3 axis[3];
  glm::dvec3 to_world(const glm::dvec3& local) const {
    return local.x * axis[0] + local.y * axis[1] + local.z * axis[2];
  }
  glm::dvec3 to_local(const glm::dvec3& world) const {
    return {glm::dot(world, axis[0]), glm::dot(world, axis[1]), glm::dot(world, axis[2])};
  }
};

Frame3 random_frame(Rng& rng) {
  const glm::dvec3 x = glm::normalize(glm::dvec3(2.0 * rng.next_float() - 1.0, 2.0 * rng.next_float() - 1.0,
                                                 2.0 * rng.next_float() - 1.0 + 1e-3));
  const glm::dvec3 y = random_tangent(rng, x);
  return {{x, y, glm::cross(x, y)}};
}

// Inside a closed box of length `size` and square section size/aspect, rotated at random (each face two
// triangles, so the long faces are slivers of the aspect ratio), rays from inside that meet a long face at a
// grazing angle. Every ray must hit: the box is closed, so a watertight backend may not lose one.
Scenario closed_box(const glm::dvec3& center, double size, double aspect, std::size_t rays, std::uint64_t seed) {
  Scenario s;
  s.name = fmt::format("box-{:g}", aspect);
  Rng rng(seed, 2);
  const Frame3 frame = random_frame(rng);
  const glm::dvec3 half(0.5 * size, 0.5 * size / aspect, 0.5 * size / aspect);
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    const glm::dvec3 corner((i & 1) ? half.x : -half.x, (i & 2) ? half.y : -half.y, (i & 4) ? half.z : -half.z);
    mesh.positions.push_back(to_float(center + frame.to_world(corner)));
  }
  // Faces counter-clockwise seen from outside (corner i has bit 0 = x, bit 1 = y, bit 2 = z; the frame is
  // right-handed, so the winding survives the rotation).
  const std::uint32_t quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& q : quads) {
    mesh.indices.push_back({q[0], q[1], q[2]});
    mesh.indices.push_back({q[0], q[2], q[3]});
  }
  ensure_vertex_padding(mesh.positions);
  s.geometry.meshes.push_back(std::move(mesh));
  const glm::dvec3 normals[4] = {{0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};  // the long faces, outward (local)
  // Origins are drawn again when, rounded to float, they are not clearly inside (a tenth of the section from
  // every face, which the float corners miss by a few ulps at most).
  for (std::size_t attempts = 0; s.rays.size() < rays && attempts < 100 * rays; ++attempts) {
    const glm::dvec3 n = normals[rng.next_below(4)];
    glm::dvec3 target(half.x * (1.6 * rng.next_float() - 0.8), half.y * (2.0 * rng.next_float() - 1.0),
                      half.z * (2.0 * rng.next_float() - 1.0));
    for (int k = 1; k < 3; ++k)
      if (n[k] != 0.0) target[k] = n[k] * half[k];
    const double theta = grazing_angle(rng);
    const glm::dvec3 along(rng.next_below(2) == 0 ? 1.0 : -1.0, 0.0, 0.0);
    const glm::dvec3 d = std::cos(theta) * along + std::sin(theta) * n;
    const double distance = std::min(size * (0.05 + 0.3 * rng.next_float()), 0.8 * half.y / std::sin(theta));
    Ray ray;
    ray.org = to_float(center + frame.to_world(target - distance * d));
    ray.dir = to_float(frame.to_world(d));
    const glm::dvec3 local = frame.to_local(glm::dvec3(ray.org) - center);
    const glm::dvec3 margin = half - glm::dvec3(0.0, 0.1 * half.y, 0.1 * half.z);
    if (std::fabs(local.x) < margin.x && std::fabs(local.y) < margin.y && std::fabs(local.z) < margin.z)
      s.rays.push_back(ray);
  }
  return s;
}

Outcome grazing_slivers(const std::string& backend_name, const StressOptions& options) {
  Outcome out;
  const double offsets[] = {0.0, 1e4};
  std::size_t rays = 0, wrong = 0, exact_t = 0, hits = 0;
  std::map<std::string, std::size_t> wrong_by_reason;  // wrong answers (closest and any hit) by the arbiter's reason
  double max_rel = 0.0;
  std::string per_scenario;
  BackendTraits traits;
  for (const double offset : offsets) {
    // Near 1.5e4 one float ulp is 2^-9: the shapes grow with the offset (length 1e4 there) so that a 1e5:1 sliver
    // is still about fifty ulps wide; angles, aspect ratios and positions relative to the size stay the same.
    const double size = offset > 1.0 ? offset : 1.0;
    const glm::dvec3 center(offset, 0.5 * offset, -0.75 * offset);
    std::vector<Scenario> scenarios;
    scenarios.push_back(open_slivers(center, size, scaled(100, options, 4), 11));
    for (const double aspect : kAspects)
      scenarios.push_back(closed_box(center, size, aspect, scaled(500, options, 16), 13));
    for (Scenario& sc : scenarios) {
      LoadReport report;
      clean_geometry(sc.geometry, report);
      const auto backend = build_backend(backend_name, sc.geometry);
      traits = backend->traits();
      const arbiter::Arbiter arbiter(sc.geometry);
      std::size_t scenario_wrong = 0;
      for (const Ray& ray : sc.rays) {
        Hit hit;
        backend->intersect(ray, hit);
        const bool occluded = backend->occluded(ray);
        const arbiter::Ruling closest = arbiter.rule_closest(ray, hit, traits);
        const arbiter::Ruling any = arbiter.rule_occluded(ray, occluded, traits);
        ++rays;
        hits += hit.found() ? 1 : 0;
        if (closest.t_rel_error >= 0.0) max_rel = std::max(max_rel, closest.t_rel_error);
        if (hit.found() && closest.exact.found() && hit.geom_id == closest.exact.geom_id &&
            hit.prim_id == closest.exact.prim_id && hit.t == closest.exact.t)
          ++exact_t;
        for (const arbiter::Ruling* r : {&closest, &any})
          if (!r->right) ++wrong_by_reason[std::string(arbiter::to_string(r->reason))];
        const bool bad = !closest.right || !any.right;
        scenario_wrong += bad ? 1 : 0;
        if (bad && out.json["wrong_examples"].size() < 5) {
          const arbiter::Ruling& r = closest.right ? any : closest;
          out.json["wrong_examples"].push_back(
              {{"scenario", sc.name},
               {"offset", offset},
               {"ray", fmt::format("org ({:a}, {:a}, {:a}) dir ({:a}, {:a}, {:a})", ray.org.x, ray.org.y, ray.org.z,
                                   ray.dir.x, ray.dir.y, ray.dir.z)},
               {"reason", arbiter::to_string(r.reason)},
               {"detail", r.detail}});
        }
      }
      wrong += scenario_wrong;
      per_scenario += fmt::format(" {}@{:g}:{}", sc.name, offset, scenario_wrong);
      out.json["scenarios"][fmt::format("{}@{:g}", sc.name, offset)] = {{"rays", sc.rays.size()}, {"wrong", scenario_wrong}};
    }
  }
  out.status = wrong == 0 ? Status::Pass : Status::Fail;
  out.figures = fmt::format("{} rays, {} hits, {} wrong (arbiter); t exactly the exact one on {}/{} hits, max rel t err "
                            "{:.2g}; wrong by scenario{}",
                            rays, hits, wrong, exact_t, hits, max_rel, per_scenario);
  out.json["rays"] = rays;
  out.json["wrong"] = wrong;
  out.json["t_bit_identical_to_exact"] = exact_t;
  out.json["hits"] = hits;
  out.json["max_t_rel_error"] = max_rel;
  out.json["wrong_answers_by_reason"] = wrong_by_reason;
  // Embree computes t in float: at grazing angles its error is about an ulp over the sine of the angle, beyond
  // the arbiter's tolerance at 1e-4 degrees. Reported, not required (issue 11).
  const bool embree = backend_name == "embree" || backend_name == "embree-fast";
  set_requirement(out, backend_name, !embree, "t within the arbiter's tolerance at grazing angles");
  return out;
}

}  // namespace

void add_grazing_slivers_case(std::vector<StressCase>& cases) {
  cases.push_back({"grazing-slivers", "geometry",
                   "triangles of aspect 1e2-1e5 hit at 1e-4 to 1 degree, open and inside closed boxes, near the "
                   "origin and at 1e4: every answer ruled by the arbiter against the exact backend",
                   grazing_slivers});
}

}  // namespace twinray::stress
