// The exact backend: bit for bit the brute-force answer wherever brute's float edge decision agrees with the
// exact one (every other difference is one the arbiter explains as an edge), ties to the lowest ids, invalid
// rays, a candidate search that never loses a hit, and thread safety.

#include "backends/brute/brute_backend.h"
#include "backends/exact/exact_backend.h"
#include "core/exact/exact_triangle.h"
#include "core/sampling/rng.h"
#include "core/scene/procedural.h"
#include "harness/arbiter/arbiter.h"
#include "ray_test_util.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <vector>

namespace twinray {
namespace {

using test::kInf;
using test::same_hit_bits;

// Random rays through a box of half extent `spread`, half of them aimed at a random point (so most hit),
// one in four with a zero direction component, a mix of interval bounds.
std::vector<Ray> exact_suite_rays(std::uint64_t seed, float spread, int n) {
  Rng rng(seed, 0);
  const auto sym = [&rng] { return 2.0f * rng.next_float() - 1.0f; };
  std::vector<Ray> rays(static_cast<std::size_t>(n));
  for (Ray& r : rays) {
    r.org = spread * glm::vec3(sym(), sym(), sym());
    const glm::vec3 aim = spread * glm::vec3(sym(), sym(), sym());
    r.dir = rng.next_below(2) == 0 ? glm::vec3(sym(), sym(), sym()) : aim - r.org;
    if (rng.next_below(4) == 0) r.dir[static_cast<int>(rng.next_below(3))] = rng.next_below(2) ? 0.0f : -0.0f;
    if (r.dir == glm::vec3(0.0f)) r.dir.z = 1.0f;
    r.tmin = rng.next_below(4) == 0 ? 0.5f * rng.next_float() : 0.0f;
    r.tmax = rng.next_below(4) == 0 ? r.tmin + 2.0f * rng.next_float() : kInf;
  }
  return rays;
}

// Rays exactly through vertices and edge midpoints of grid_mesh(16, 16) along small-integer directions.
std::vector<Ray> exact_suite_grid_rays(std::uint64_t seed, int n) {
  Rng rng(seed, 0);
  std::vector<Ray> rays(static_cast<std::size_t>(n));
  for (Ray& r : rays) {
    const glm::vec3 target(0.5f * static_cast<float>(rng.next_below(33)), 0.5f * static_cast<float>(rng.next_below(33)), 0.0f);
    glm::vec3 d(static_cast<float>(static_cast<int>(rng.next_below(7)) - 3),
                static_cast<float>(static_cast<int>(rng.next_below(7)) - 3),
                static_cast<float>(static_cast<int>(rng.next_below(9)) - 4));
    if (d.z == 0.0f) d.z = -1.0f;
    r.org = target - 0.75f * d;
    r.dir = d;
  }
  return rays;
}

struct Agreement {
  std::size_t rays = 0, hits = 0, identical = 0, edge = 0;
};

// Every ray: exact and brute answer identically, or brute's answer is ruled right as an edge difference.
Agreement expect_exact_agrees_with_brute(const SceneGeometry& geometry, const std::vector<Ray>& rays) {
  const std::unique_ptr<Backend> brute = make_brute_backend();
  const std::unique_ptr<Backend> exact = make_exact_backend();
  brute->build(geometry);
  exact->build(geometry);
  const arbiter::Arbiter arbiter(geometry);
  Agreement a;
  int reported = 0;
  for (const Ray& ray : rays) {
    Hit b, e;
    const bool found = brute->intersect(ray, b);
    exact->intersect(ray, e);
    ++a.rays;
    a.hits += found ? 1 : 0;
    const bool occluded_b = brute->occluded(ray), occluded_e = exact->occluded(ray);
    EXPECT_EQ(occluded_e, e.found());
    if (same_hit_bits(b, e) && occluded_b == occluded_e) {
      ++a.identical;
      continue;
    }
    ++a.edge;
    const arbiter::Ruling closest = arbiter.rule_closest(ray, b, brute->traits());
    const arbiter::Ruling any = arbiter.rule_occluded(ray, occluded_b, brute->traits());
    const bool explained = closest.right && any.right &&
                           (same_hit_bits(b, e) || closest.reason == arbiter::Reason::Edge) &&
                           (occluded_b == occluded_e || any.reason == arbiter::Reason::Edge);
    if (!explained && ++reported <= 5)
      ADD_FAILURE() << "brute " << b.geom_id << "/" << b.prim_id << " t=" << b.t << ", exact " << e.geom_id << "/"
                    << e.prim_id << " t=" << e.t << ": " << arbiter::to_string(closest.reason) << " " << closest.detail
                    << " | any: " << arbiter::to_string(any.reason) << " " << any.detail;
  }
  return a;
}

TEST(ExactBackend, AgreesWithBruteExceptWhereTheFloatEdgeTestDiffers) {
  const Agreement soup = expect_exact_agrees_with_brute(random_triangle_soup(1000, 7), exact_suite_rays(1, 1.5f, 2500));
  EXPECT_GT(soup.hits, soup.rays / 4);
  EXPECT_GE(soup.identical, soup.rays - soup.rays / 1000);
  const Agreement sphere =
      expect_exact_agrees_with_brute(tessellated_sphere({0.5f, -0.25f, 0.0f}, 1.0f, 3), exact_suite_rays(2, 1.5f, 2500));
  EXPECT_GT(sphere.hits, sphere.rays / 4);
  EXPECT_GE(sphere.identical, sphere.rays - sphere.rays / 1000);
  const Agreement mixed = expect_exact_agrees_with_brute(mixed_spheres_and_triangles(100, 400, 9), exact_suite_rays(3, 1.5f, 2500));
  EXPECT_GT(mixed.hits, mixed.rays / 4);
  EXPECT_GE(mixed.identical, mixed.rays - mixed.rays / 1000);
  const Agreement spheres = expect_exact_agrees_with_brute(random_spheres(200, 10), exact_suite_rays(4, 1.5f, 2500));
  EXPECT_GT(spheres.hits, spheres.rays / 10);
  EXPECT_EQ(spheres.identical, spheres.rays);  // no edges on spheres: the roots are correctly rounded by both
  // Rays exactly through edges and vertices: the fill rule of the exact frame and of the float frame agree
  // whenever the float shear is exact (dyadic directions), and differ only at edges otherwise.
  const Agreement grid = expect_exact_agrees_with_brute(grid_mesh(16, 16), exact_suite_grid_rays(5, 2500));
  EXPECT_GT(grid.hits, grid.rays / 2);
}

TEST(ExactBackend, TiesGoToTheLowestIds) {
  SceneGeometry g = random_triangle_soup(300, 8);
  g.meshes.push_back(g.meshes[0]);
  g.meshes[1].geom_id = 2;
  g.spheres.push_back({1, glm::vec3(0.2f, 0.1f, 0.0f), 0.3f});
  g.spheres.push_back({3, glm::vec3(0.2f, 0.1f, 0.0f), 0.3f});
  const std::unique_ptr<Backend> exact = make_exact_backend();
  exact->build(g);
  std::size_t hits = 0;
  for (const Ray& ray : exact_suite_rays(6, 1.5f, 3000)) {
    Hit h;
    if (!exact->intersect(ray, h)) continue;
    ++hits;
    EXPECT_TRUE(h.geom_id == 0 || h.geom_id == 1) << h.geom_id;
  }
  EXPECT_GT(hits, 300u);
}

TEST(ExactBackend, InvalidRaysMissWithoutWork) {
  const SceneGeometry g = mixed_spheres_and_triangles(50, 200, 3);
  const std::unique_ptr<Backend> exact = make_exact_backend();
  exact->build(g);
  std::vector<Ray> invalid(5);
  invalid[0].org = {test::kNaN, 0.0f, 0.0f};
  invalid[1].dir = {0.0f, 0.0f, 0.0f};
  invalid[2].dir = {kInf, 0.0f, 0.0f};
  invalid[3].tmin = -1.0f;
  invalid[4].tmin = 2.0f, invalid[4].tmax = 1.0f;
  QueryStats stats;
  for (const Ray& ray : invalid) {
    Hit hit;
    hit.geom_id = 5;
    EXPECT_FALSE(exact->intersect(ray, hit, &stats));
    EXPECT_FALSE(hit.found());
    EXPECT_FALSE(exact->occluded(ray, &stats));
  }
  EXPECT_EQ(stats.nodes_visited + stats.primitives_tested, 0u);
  EXPECT_EQ(exact->name(), "exact");
  EXPECT_TRUE(exact->traits().watertight && exact->traits().honours_ties);
}

// The candidate search the arbiter relies on returns every primitive the exact ray hits in the interval.
TEST(ExactBackend, PrimitivesNearContainEveryExactHit) {
  const SceneGeometry g = random_triangle_soup(500, 11);
  ExactBackend exact;
  exact.build(g);
  const TriangleMesh& mesh = g.meshes[0];
  std::size_t checked = 0;
  for (const Ray& ray : exact_suite_rays(7, 1.5f, 200)) {
    std::vector<PrimitiveRef> near;
    exact.primitives_near(ray, 0.0, ray.tmin, ray.tmax, near);
    for (std::size_t i = 0; i < mesh.indices.size(); ++i) {
      const glm::uvec3& tri = mesh.indices[i];
      const exact::TriangleCrossing c = exact::intersect_triangle_exact(
          {glm::dvec3(ray.org), glm::dvec3(ray.dir), glm::dvec3(mesh.positions[tri.x]), glm::dvec3(mesh.positions[tri.y]),
           glm::dvec3(mesh.positions[tri.z])});
      if (!c.hit || !(c.t >= ray.tmin && c.t <= ray.tmax)) continue;
      ++checked;
      EXPECT_NE(std::find(near.begin(), near.end(), PrimitiveRef{0, static_cast<std::uint32_t>(i)}), near.end());
    }
  }
  EXPECT_GT(checked, 40u);
}

TEST(ExactBackend, ConcurrentQueriesMatchSerialOnes) {
  const SceneGeometry g = mixed_spheres_and_triangles(60, 300, 5);
  const std::unique_ptr<Backend> exact = make_exact_backend();
  exact->build(g);
  const std::vector<Ray> rays = exact_suite_rays(8, 1.5f, 2000);
  std::vector<Hit> serial(rays.size()), parallel(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) exact->intersect(rays[i], serial[i]);
  tbb::parallel_for(std::size_t{0}, rays.size(), [&](std::size_t i) { exact->intersect(rays[i], parallel[i]); });
  for (std::size_t i = 0; i < rays.size(); ++i) EXPECT_TRUE(same_hit_bits(serial[i], parallel[i])) << i;
}

}  // namespace
}  // namespace twinray
