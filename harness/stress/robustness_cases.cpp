// Robustness cases: NaN / Inf / degenerate rays (single and batched), extreme but valid direction
// magnitudes, and NaN / Inf vertices removed at build time. Sources and reasoning: docs/stress.md.

#include "harness/stress/stress_case.h"
#include "harness/stress/stress_support.h"
#include "core/geometry/ray.h"
#include "core/sampling/rng.h"
#include "core/sampling/warp.h"
#include "core/scene/geometry_cleanup.h"
#include "core/scene/procedural.h"

#include <fmt/core.h>
#include <glm/geometric.hpp>

#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

namespace twinray::stress {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// Every way a ray can be invalid (core/geometry/ray.h), built from a valid ray aimed into the scene.
std::vector<Ray> invalid_variants(const Ray& valid) {
  std::vector<Ray> out;
  for (const float bad : {kNaN, kInf, -kInf}) {
    for (int k = 0; k < 3; ++k) {
      Ray r = valid;
      r.org[k] = bad;
      out.push_back(r);
      r = valid;
      r.dir[k] = bad;
      out.push_back(r);
    }
    Ray r = valid;
    r.tmin = bad;
    out.push_back(r);
    if (bad != kInf) {  // tmax = +inf is valid
      r = valid;
      r.tmax = bad;
      out.push_back(r);
    }
  }
  Ray r = valid;
  r.dir = glm::vec3(0.0f);
  out.push_back(r);
  r = valid;
  r.dir = glm::vec3(-0.0f);
  out.push_back(r);
  r = valid;
  r.tmin = -1.0f;
  out.push_back(r);
  r = valid;
  r.tmin = 2.0f;
  r.tmax = 1.0f;
  out.push_back(r);
  r = valid;
  r.org = glm::vec3(kNaN);
  r.dir = glm::vec3(kNaN);
  r.tmin = kNaN;
  r.tmax = kNaN;
  out.push_back(r);
  return out;
}

// Invalid rays must be misses for closest and any hit, single and batched, without a tree sweep: a
// backend that counts traversal must report no node and no primitive touched. Valid rays with direction
// magnitudes 1e-15 and 1e15 must find the same primitive as the unit direction (t scales by 1/|dir|).
Outcome invalid_rays(const std::string& backend_name, const StressOptions& options) {
  Outcome out;
  const SceneGeometry geometry = mixed_spheres_and_triangles(200, 20000, 5);
  const auto backend = build_backend(backend_name, geometry);
  const std::size_t n_base = scaled(400, options, 20);
  Rng rng(21, 0);
  std::vector<Ray> valid_rays, invalid;
  for (std::size_t i = 0; i < n_base; ++i) {
    Ray ray;
    ray.org = 3.0f * sample_uniform_sphere({rng.next_float(), rng.next_float()});
    ray.dir = glm::normalize(0.5f * sample_uniform_sphere({rng.next_float(), rng.next_float()}) - ray.org);
    valid_rays.push_back(ray);
    for (const Ray& r : invalid_variants(ray)) invalid.push_back(r);
  }
  // Single-ray queries.
  QueryStats stats;
  std::size_t wrong = 0;
  const auto start = std::chrono::steady_clock::now();
  for (const Ray& r : invalid) {
    Hit hit;
    hit.t = 1.0f;
    hit.geom_id = 0;  // stale contents must be reset to a miss
    const bool found = backend->intersect(r, hit, &stats);
    wrong += (found || hit.found()) ? 1 : 0;
    wrong += backend->occluded(r, &stats) ? 1 : 0;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Batched: invalid and valid rays interleaved; valid ones must match their single-ray answers.
  std::vector<Ray> mixed;
  for (std::size_t i = 0; i < valid_rays.size(); ++i) {
    mixed.push_back(valid_rays[i]);
    mixed.push_back(invalid[i * (invalid.size() / valid_rays.size()) + i % 7]);
  }
  std::vector<Hit> hits(mixed.size());
  std::vector<std::uint8_t> occluded(mixed.size());
  backend->intersect(std::span<const Ray>(mixed), std::span<Hit>(hits));
  backend->occluded(std::span<const Ray>(mixed), std::span<std::uint8_t>(occluded));
  std::size_t batch_wrong = 0;
  for (std::size_t i = 0; i < mixed.size(); ++i) {
    if (i % 2 == 1) {
      batch_wrong += (hits[i].found() || occluded[i]) ? 1 : 0;
    } else {
      Hit single;
      backend->intersect(mixed[i], single);
      const bool same = single.found() == hits[i].found() &&
                        (!single.found() || (single.geom_id == hits[i].geom_id && single.prim_id == hits[i].prim_id));
      batch_wrong += same && (occluded[i] != 0) == single.found() ? 0 : 1;
    }
  }
  // Extreme but valid direction magnitudes.
  std::size_t magnitude_wrong = 0, magnitude_rays = 0;
  for (const Ray& ray : valid_rays) {
    Hit unit;
    backend->intersect(ray, unit);
    for (const float m : {1e-15f, 1e15f}) {
      Ray r = ray;
      r.dir *= m;
      Hit hit;
      backend->intersect(r, hit);
      ++magnitude_rays;
      const bool same = unit.found() == hit.found() &&
                        (!unit.found() || (unit.geom_id == hit.geom_id && unit.prim_id == hit.prim_id &&
                                           relative_difference(unit.t, static_cast<double>(hit.t) * m) < 1e-4));
      magnitude_wrong += same ? 0 : 1;
    }
  }
  const bool counts = backend->traits().counts_traversal;
  const std::uint64_t touched = stats.nodes_visited + stats.primitives_tested;
  const bool ok = wrong == 0 && batch_wrong == 0 && magnitude_wrong == 0 && (!counts || touched == 0);
  out.status = ok ? Status::Pass : Status::Fail;
  out.figures = fmt::format("{} invalid rays: {} not misses, {:.0f} ns/ray, nodes+prims touched {}; batch {} wrong; "
                            "|dir| 1e-15/1e15: {}/{} differ",
                            invalid.size(), wrong, 1e9 * seconds / static_cast<double>(2 * invalid.size()),
                            counts ? std::to_string(touched) : std::string("n/a"), batch_wrong, magnitude_wrong,
                            magnitude_rays);
  out.json = {{"invalid_rays", invalid.size()},  {"not_misses", wrong},
              {"seconds", seconds},              {"touched", counts ? touched : 0},
              {"batch_wrong", batch_wrong},      {"magnitude_rays", magnitude_rays},
              {"magnitude_wrong", magnitude_wrong}};
  set_requirement(out, backend_name, true, "");
  return out;
}

// Triangles with a NaN or Inf vertex are dropped by clean_geometry and counted; the rest keep their order
// and are hit where they should be. The backend is built on the cleaned geometry (its invariant).
Outcome nonfinite_vertices(const std::string& backend_name, const StressOptions&) {
  Outcome out;
  SceneGeometry geometry = grid_mesh(8, 8);  // 128 triangles; triangle 2 * (j * 8 + i) + {0,1} in square (i, j)
  TriangleMesh& mesh = geometry.meshes.front();
  // Poison three vertices: each belongs to up to six triangles around it.
  const std::uint32_t poisoned[] = {1 * 9 + 1, 4 * 9 + 5, 7 * 9 + 7};
  const float values[] = {kNaN, kInf, -kInf};
  for (int k = 0; k < 3; ++k) mesh.positions[poisoned[k]][k] = values[k];
  std::vector<bool> expect_kept(mesh.indices.size(), true);
  std::size_t expect_dropped = 0;
  for (std::size_t t = 0; t < mesh.indices.size(); ++t)
    for (int c = 0; c < 3; ++c)
      for (const std::uint32_t p : poisoned)
        if (mesh.indices[t][c] == p && expect_kept[t]) {
          expect_kept[t] = false;
          ++expect_dropped;
        }
  LoadReport report;
  clean_geometry(geometry, report);
  const auto backend = build_backend(backend_name, geometry);
  // Shoot at the centroid of every original triangle (computed from the unpoisoned grid).
  std::size_t wrong = 0, rays = 0;
  std::uint32_t kept_id = 0;
  const SceneGeometry original = grid_mesh(8, 8);
  const TriangleMesh& om = original.meshes.front();
  for (std::size_t t = 0; t < om.indices.size(); ++t) {
    const glm::vec3 c = (om.positions[om.indices[t][0]] + om.positions[om.indices[t][1]] +
                         om.positions[om.indices[t][2]]) / 3.0f;
    Ray ray;
    ray.org = c + glm::vec3(0, 0, 1);
    ray.dir = {0, 0, -1};
    Hit hit;
    const bool found = backend->intersect(ray, hit);
    ++rays;
    if (expect_kept[t]) {
      wrong += (found && hit.prim_id == kept_id) ? 0 : 1;
      ++kept_id;
    } else {
      wrong += found ? 1 : 0;  // its square's other triangles do not cover the centroid
    }
  }
  const bool ok = report.nonfinite_triangles == expect_dropped && wrong == 0;
  out.status = ok ? Status::Pass : Status::Fail;
  out.figures = fmt::format("dropped {} non-finite triangles (want {}), {}/{} rays wrong", report.nonfinite_triangles,
                            expect_dropped, wrong, rays);
  out.json = {{"dropped", report.nonfinite_triangles}, {"expected_dropped", expect_dropped}, {"wrong", wrong}};
  set_requirement(out, backend_name, true, "");
  return out;
}

}  // namespace

void add_robustness_cases(std::vector<StressCase>& cases) {
  cases.push_back({"invalid-rays", "robustness",
                   "NaN/Inf/zero/reversed rays are misses (single and batched) without touching the tree",
                   invalid_rays});
  cases.push_back({"nonfinite-vertices", "robustness",
                   "triangles with NaN/Inf vertices are dropped at build, counted, and the rest keep their ids",
                   nonfinite_vertices});
}

}  // namespace twinray::stress
