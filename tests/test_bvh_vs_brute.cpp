// The bvh and bvh8 backends against the brute-force oracle: on every ray, the same hit (geometry id,
// primitive id) and bit-identical t, u, v and normal, for closest hits and any hits, over scenes chosen to
// provoke ties, exact edge and vertex crossings, signed-zero directions and mixed primitive kinds. Each
// tree runs on every instruction set this CPU has (SSE2, AVX2, AVX-512 kernels), so all paths are shown
// bit-identical to the oracle and therefore to each other.

#include "backends/brute/brute_backend.h"
#include "backends/bvh/bvh_backend.h"
#include "backends/wide/wide_backend.h"
#include "core/sampling/rng.h"
#include "core/scene/procedural.h"
#include "coplanar_tiles_test_util.h"
#include "ray_test_util.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace twinray {
namespace {

using test::kInf;
using test::same_bits;

constexpr int kRaysPerScene = 20000;

glm::vec3 random_direction(Rng& rng) {
  glm::vec3 d(2.0f * rng.next_float() - 1.0f, 2.0f * rng.next_float() - 1.0f, 2.0f * rng.next_float() - 1.0f);
  // One ray in four has one or two exactly zero components, with either sign.
  if (rng.next_below(4) == 0) {
    const std::uint32_t k = rng.next_below(3);
    d[static_cast<int>(k)] = rng.next_below(2) ? 0.0f : -0.0f;
    if (rng.next_below(2)) d[static_cast<int>((k + 1) % 3)] = rng.next_below(2) ? 0.0f : -0.0f;
  }
  if (d == glm::vec3(0.0f)) d.x = 1.0f;
  return d;
}

// Random rays through a box of half extent `spread` around `center`, with a mix of interval bounds.
std::vector<Ray> random_rays(Rng& rng, const glm::vec3& center, float spread, int n) {
  std::vector<Ray> rays(static_cast<std::size_t>(n));
  for (Ray& r : rays) {
    r.org = center + spread * glm::vec3(2.0f * rng.next_float() - 1.0f, 2.0f * rng.next_float() - 1.0f,
                                        2.0f * rng.next_float() - 1.0f);
    // Half the rays aim at a random point of the scene, so that most of them hit something.
    const glm::vec3 aim = center + spread * glm::vec3(2.0f * rng.next_float() - 1.0f, 2.0f * rng.next_float() - 1.0f,
                                                      2.0f * rng.next_float() - 1.0f);
    r.dir = rng.next_below(2) == 0 ? random_direction(rng) : aim - r.org;
    if (r.dir == glm::vec3(0.0f)) r.dir.z = 1.0f;
    r.tmin = rng.next_below(4) == 0 ? 0.5f * rng.next_float() : 0.0f;
    r.tmax = rng.next_below(4) == 0 ? r.tmin + 2.0f * rng.next_float() : kInf;
  }
  return rays;
}

// Rays through exact vertices, edge midpoints and diagonal points of grid_mesh(16, 16), from both sides,
// along small-integer directions (so the ray passes exactly through the target).
std::vector<Ray> grid_edge_rays(Rng& rng, int n) {
  std::vector<Ray> rays(static_cast<std::size_t>(n));
  for (Ray& r : rays) {
    const glm::vec3 target(static_cast<float>(rng.next_below(33)) * 0.5f, static_cast<float>(rng.next_below(33)) * 0.5f,
                           0.0f);
    glm::vec3 dir(static_cast<float>(static_cast<int>(rng.next_below(7)) - 3),
                  static_cast<float>(static_cast<int>(rng.next_below(7)) - 3),
                  static_cast<float>(static_cast<int>(rng.next_below(9)) - 4));
    if (dir.z == 0.0f) dir.z = rng.next_below(2) ? -1.0f : 1.0f;
    if (rng.next_below(3) == 0) dir.x = rng.next_below(2) ? 0.0f : -0.0f;
    r.org = target - 0.75f * dir;
    r.dir = dir;
  }
  return rays;
}

std::string describe(const Ray& r) {
  return "org (" + std::to_string(r.org.x) + ", " + std::to_string(r.org.y) + ", " + std::to_string(r.org.z) +
         ") dir (" + std::to_string(r.dir.x) + ", " + std::to_string(r.dir.y) + ", " + std::to_string(r.dir.z) +
         ") [" + std::to_string(r.tmin) + ", " + std::to_string(r.tmax) + "]";
}

std::size_t expect_identical_to_brute(const SceneGeometry& geometry, const std::vector<Ray>& rays, Backend& tree);

// bvh and bvh8, each on every instruction set this CPU can run.
std::vector<std::pair<std::string, std::unique_ptr<Backend>>> trees_on_every_isa() {
  std::vector<std::pair<std::string, std::unique_ptr<Backend>>> trees;
  for (const Isa isa : runnable_isas()) {
    trees.emplace_back("bvh/" + std::string(to_string(isa)), make_bvh_backend({}, isa));
    trees.emplace_back("bvh8/" + std::string(to_string(isa)), make_wide_backend({}, isa));
    // The nearest-first any-hit order too, whichever order the build picks for the scene (wide_any_order.h).
    WideBuildOptions nearest;
    nearest.any_hit_order = AnyHitOrder::kNearest;
    trees.emplace_back("bvh8/" + std::string(to_string(isa)) + "/nearest", make_wide_backend(nearest, isa));
  }
  return trees;
}

// Compares every ray; returns the number of closest hits (so a scene that is never hit cannot pass).
std::size_t expect_identical(const SceneGeometry& geometry, const std::vector<Ray>& rays) {
  std::size_t hits = 0;
  for (auto& [name, tree] : trees_on_every_isa()) {
    SCOPED_TRACE(name);
    hits = expect_identical_to_brute(geometry, rays, *tree);
  }
  return hits;
}

std::size_t expect_identical_to_brute(const SceneGeometry& geometry, const std::vector<Ray>& rays, Backend& tree) {
  const std::unique_ptr<Backend> brute = make_brute_backend();
  Backend* bvh = &tree;
  brute->build(geometry);
  bvh->build(geometry);
  QueryStats brute_stats, bvh_stats;
  std::size_t hits = 0, mismatches = 0;
  for (const Ray& ray : rays) {
    Hit a, b;
    const bool found_a = brute->intersect(ray, a, &brute_stats);
    const bool found_b = bvh->intersect(ray, b, &bvh_stats);
    const bool same = found_a == found_b && test::same_hit_bits(a, b);
    const bool occluded_a = brute->occluded(ray, &brute_stats);
    const bool occluded_b = bvh->occluded(ray, &bvh_stats);
    if (!same || occluded_a != found_a || occluded_b != found_a) {
      if (++mismatches <= 5)
        ADD_FAILURE() << describe(ray) << "\n brute: " << found_a << " " << a.geom_id << "/" << a.prim_id << " t=" << a.t
                      << " u=" << a.u << " v=" << a.v << " occluded=" << occluded_a << "\n bvh:   " << found_b << " "
                      << b.geom_id << "/" << b.prim_id << " t=" << b.t << " u=" << b.u << " v=" << b.v
                      << " occluded=" << occluded_b;
    }
    if (found_a) {
      ++hits;
      EXPECT_TRUE(std::isfinite(a.u) && std::isfinite(a.v) && std::isfinite(a.ng.x));
    }
  }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_EQ(bvh_stats.queries, 2 * rays.size());
  // The point of a BVH: far fewer primitive tests than the oracle.
  EXPECT_LT(bvh_stats.primitives_tested * 4, brute_stats.primitives_tested);
  return hits;
}

TEST(BvhVsBrute, TriangleSoup) {
  Rng rng(1, 0);
  const std::size_t hits = expect_identical(random_triangle_soup(1000, 7), random_rays(rng, glm::vec3(0.0f), 1.5f, kRaysPerScene));
  EXPECT_GT(hits, kRaysPerScene / 4u);
}

TEST(BvhVsBrute, TessellatedSphereFromInsideAndOutside) {
  Rng rng(2, 0);
  const std::size_t hits =
      expect_identical(tessellated_sphere(glm::vec3(0.5f, -0.25f, 0.0f), 1.0f, 3), random_rays(rng, {0.5f, -0.25f, 0.0f}, 1.5f, kRaysPerScene));
  EXPECT_GT(hits, kRaysPerScene / 4u);
}

TEST(BvhVsBrute, GridWithRaysThroughEdgesAndVertices) {
  Rng rng(3, 0);
  const std::size_t hits = expect_identical(grid_mesh(16, 16), grid_edge_rays(rng, kRaysPerScene));
  EXPECT_GT(hits, kRaysPerScene / 4u);
}

TEST(BvhVsBrute, SpheresMixedWithTriangles) {
  Rng rng(4, 0);
  const std::size_t hits = expect_identical(mixed_spheres_and_triangles(100, 400, 9), random_rays(rng, glm::vec3(0.0f), 1.5f, kRaysPerScene));
  EXPECT_GT(hits, kRaysPerScene / 4u);
}

TEST(BvhVsBrute, SpheresOnly) {
  Rng rng(5, 0);
  const std::size_t hits = expect_identical(random_spheres(200, 10), random_rays(rng, glm::vec3(0.0f), 1.5f, kRaysPerScene));
  EXPECT_GT(hits, kRaysPerScene / 10u);
}

TEST(BvhVsBrute, DuplicatedGeometryResolvesTiesByLowestIds) {
  // Two identical meshes (geom 0 and 2) and identical duplicate spheres (geom 1 and 3): every hit is a tie
  // that only the (geom_id, prim_id) order can decide.
  SceneGeometry g = random_triangle_soup(300, 8);
  g.meshes.push_back(g.meshes[0]);
  g.meshes[1].geom_id = 2;
  g.spheres.push_back({1, glm::vec3(0.2f, 0.1f, 0.0f), 0.3f});
  g.spheres.push_back({3, glm::vec3(0.2f, 0.1f, 0.0f), 0.3f});
  Rng rng(6, 0);
  const std::vector<Ray> rays = random_rays(rng, glm::vec3(0.0f), 1.5f, kRaysPerScene / 2);
  EXPECT_GT(expect_identical(g, rays), rays.size() / 8);
  const std::unique_ptr<Backend> bvh = make_bvh_backend();
  bvh->build(g);
  for (const Ray& ray : rays) {
    Hit hit;
    if (bvh->intersect(ray, hit)) {
      EXPECT_TRUE(hit.geom_id == 0 || hit.geom_id == 1) << hit.geom_id;
    }
  }
}

// Overlapping triangles in one plane z = 0.3 (not a dyadic number), put one per leaf by the options below:
// every crossing is a tie between triangles in different leaves, whose flat boxes the ray enters (and
// leaves) exactly at the tie's t.
SceneGeometry overlapping_coplanar_tiles() {
  Rng rng(12, 0);
  const std::vector<glm::vec3> corners = test::overlapping_tile_corners(rng, 400);
  TriangleMesh mesh;
  mesh.positions = corners;
  for (std::uint32_t first = 0; first < corners.size(); first += 3) {
    mesh.indices.push_back({first, first + 1, first + 2});
  }
  mesh.positions.reserve(mesh.positions.size() + 1);
  SceneGeometry g;
  g.meshes.push_back(mesh);
  return g;
}
using test::ray_towards_tiles;

BvhBuildOptions bvh_one_per_leaf() {
  BvhBuildOptions options;
  options.max_leaf_size = 1;
  return options;
}
WideBuildOptions wide_one_per_leaf() {
  WideBuildOptions options;
  options.binary.max_leaf_size = 1;
  options.collapse.max_leaf_size = 1;
  return options;
}

// The box's computed entry may exceed the correctly rounded t by an ulp or two; the traversal must still
// visit the box, or the tie goes to whichever triangle it found first (issue 11, found by the arbiter on
// Sponza's floor).
TEST(BvhVsBrute, CoplanarTiesInDifferentLeaves) {
  const SceneGeometry g = overlapping_coplanar_tiles();
  // One triangle per leaf in both trees, so the coplanar triangles sit in flat boxes of their own.
  std::vector<std::unique_ptr<Backend>> trees;
  trees.push_back(std::make_unique<BvhBackend>(bvh_one_per_leaf()));
  trees.push_back(std::make_unique<WideBackend>(wide_one_per_leaf()));
  const std::unique_ptr<Backend> brute = make_brute_backend();
  brute->build(g);
  for (const std::unique_ptr<Backend>& tree : trees) {
    tree->build(g);
    Rng rays(13, 0);
    std::size_t hits = 0, differ = 0;
    for (int i = 0; i < 4000; ++i) {
      const Ray ray = ray_towards_tiles(rays);
      Hit a, b;
      hits += brute->intersect(ray, a) ? 1 : 0;
      tree->intersect(ray, b);
      differ += (a.prim_id != b.prim_id || !same_bits(a.t, b.t)) ? 1 : 0;
    }
    EXPECT_GT(hits, 2000u) << tree->name();
    EXPECT_EQ(differ, 0u) << tree->name();
  }
}

// Both ends of the interval at a tie, on every instruction set: each ray's tmin and tmax are set to the t
// brute force reports for it, so the hit lies exactly at both ends, in flat boxes that the ray enters and
// leaves at that t. The box tests compare their near distance (a lower bound of the exact one) with tmax
// and their far distance (an upper bound) with tmin, unwidened (backends/bvh/ray_box.h); with the near
// reciprocal unscaled (kSlabNearScale = 1: the box test of c1d6bc7, before the 2^-21 widening) the
// closest-hit rays lose ties and hits, and so they do with the far scale at 1.
TEST(BvhVsBrute, FlatBoxesKeepBothEndsOfTheInterval) {
  const SceneGeometry g = overlapping_coplanar_tiles();
  const std::unique_ptr<Backend> brute = make_brute_backend();
  brute->build(g);
  std::vector<Ray> rays;
  std::vector<Hit> expected;
  Rng rng(14, 0);
  for (int i = 0; i < 3000; ++i) {
    Ray ray = ray_towards_tiles(rng);
    Hit hit;
    if (!brute->intersect(ray, hit)) continue;
    ray.tmin = ray.tmax = hit.t;
    rays.push_back(ray);
    expected.push_back(hit);
  }
  ASSERT_GT(rays.size(), 1500u);
  for (const Isa isa : runnable_isas()) {
    BvhBackend bvh_tree(bvh_one_per_leaf(), isa);
    WideBackend wide_tree(wide_one_per_leaf(), isa);
    for (Backend* tree : {static_cast<Backend*>(&bvh_tree), static_cast<Backend*>(&wide_tree)}) {
      SCOPED_TRACE(std::string(tree->name()) + "/" + std::string(to_string(isa)));
      tree->build(g);
      std::size_t differ = 0, not_occluded = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        Hit b;
        const bool hit = tree->intersect(rays[i], b);
        differ += (!hit || expected[i].prim_id != b.prim_id || !same_bits(expected[i].t, b.t)) ? 1 : 0;
        not_occluded += tree->occluded(rays[i]) ? 0 : 1;
      }
      EXPECT_EQ(differ, 0u);
      EXPECT_EQ(not_occluded, 0u);
    }
  }
}

TEST(BvhVsBrute, OriginOnSlabPlaneWithZeroDirectionComponent) {
  // Two triangles sharing the edge x = 1 of the z = 0 plane, each in its own leaf, plus a far triangle so
  // the root is larger. A ray with dir.x = +-0 and org.x = 1 lies exactly in the leaves' slab planes x = 1
  // (hi of one box, lo of the other): the slab distance is 0 * inf = NaN, which must count as inside.
  SceneGeometry g;
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {2, 0, 0}, {5, 5, 5}, {6, 5, 5}, {5, 6, 5}};
  mesh.indices = {{0, 1, 2}, {1, 3, 2}, {4, 5, 6}};
  mesh.positions.reserve(mesh.positions.size() + 1);
  g.meshes.push_back(mesh);
  BvhBuildOptions one_per_leaf;
  one_per_leaf.max_leaf_size = 1;
  WideBuildOptions wide_one_per_leaf;
  wide_one_per_leaf.binary.max_leaf_size = 1;
  wide_one_per_leaf.collapse.max_leaf_size = 1;
  for (const Isa isa : runnable_isas()) {
    BvhBackend bvh_tree(one_per_leaf, isa);
    WideBackend wide_tree(wide_one_per_leaf, isa);
    for (Backend* tree : {static_cast<Backend*>(&bvh_tree), static_cast<Backend*>(&wide_tree)}) {
      Backend& bvh = *tree;
      SCOPED_TRACE(std::string(bvh.name()) + "/" + std::string(to_string(isa)));
      bvh.build(g);
      ASSERT_EQ(bvh.build_stats().leaves, 3u);
      const std::unique_ptr<Backend> brute = make_brute_backend();
      brute->build(g);
      for (float zero : {0.0f, -0.0f}) {
        for (float dz : {-1.0f, 1.0f}) {
          Ray ray;
          ray.org = {1.0f, 0.5f, -dz};
          ray.dir = {zero, zero, dz};
          Hit a, b;
          ASSERT_TRUE(brute->intersect(ray, a));
          ASSERT_TRUE(bvh.intersect(ray, b)) << "dir.x " << zero << " dz " << dz;
          EXPECT_EQ(a.prim_id, b.prim_id);
          EXPECT_EQ(b.t, 1.0f);
          EXPECT_TRUE(bvh.occluded(ray));
        }
      }
    }
  }
}

TEST(BvhVsBrute, OriginOnSlabPlanesWithNonZeroDirection) {
  // bvh8's slab test computes (org - plane) * -(scaled reciprocal) (wide_box_test_256.inl), which differs from
  // ray_box.h's (plane - org) * (scaled reciprocal) only in the sign of a zero, where the origin lies on the
  // plane. Rays starting on a triangle in the plane x = 1 (whose leaf box is flat there, so both its x planes
  // pass through the origin) and on the face x = 1 of a box spanning x in [1, 2], leaving or entering along +-x,
  // with tmin +0 and -0: every near and far x distance of those boxes is a zero. Each ray hits at t = 0 or
  // further on, so a box wrongly culled shows as a miss. The timed kernels (no statistics) against brute force.
  SceneGeometry g;
  TriangleMesh mesh;
  mesh.positions = {{1, 0, 0}, {1, 1, 0}, {1, 0, 1},            // in the plane x = 1
                    {1, 2, 0}, {2, 3, 0}, {2, 2, 1},            // x in [1, 2]
                    {1.5f, 2, -1}, {1.5f, 3.5f, -1}, {1.5f, 2, 2},  // crossed by rays along +x from x = 1
                    {8, 8, 8}, {9, 8, 8}, {8, 9, 8}};
  mesh.indices = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}, {9, 10, 11}};
  g.meshes.push_back(mesh);
  std::vector<Ray> rays;
  for (const float tmin : {0.0f, -0.0f})
    for (const float tmax : {kInf, 4.0f})
      for (const float sx : {1.0f, -1.0f})
        for (const glm::vec3 org : {glm::vec3(1.0f, 0.25f, 0.25f), glm::vec3(1.0f, 2.25f, 0.25f)}) {
          Ray ray;
          ray.org = org;
          ray.dir = {sx, 0.0625f, 0.125f};
          ray.tmin = tmin;
          ray.tmax = tmax;
          rays.push_back(ray);
        }
  const std::unique_ptr<Backend> brute = make_brute_backend();
  brute->build(g);
  std::vector<Hit> expected(rays.size());
  std::size_t brute_hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) brute_hits += brute->intersect(rays[i], expected[i]) ? 1 : 0;
  // Every ray from the triangle in x = 1 hits it at t = 0 (8 rays); those from the box's face going +x hit the
  // triangle in x = 1.5 at t = 0.5 (4 more); the face's rays going -x miss.
  ASSERT_GE(brute_hits, rays.size() / 2);
  for (auto& [name, tree] : trees_on_every_isa()) {
    SCOPED_TRACE(name);
    tree->build(g);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      Hit b;
      const bool found = tree->intersect(rays[i], b);
      EXPECT_EQ(found, expected[i].found()) << describe(rays[i]);
      EXPECT_EQ(b.prim_id, expected[i].prim_id) << describe(rays[i]);
      EXPECT_TRUE(same_bits(b.t, expected[i].t)) << describe(rays[i]);
      EXPECT_EQ(tree->occluded(rays[i]), expected[i].found()) << describe(rays[i]);
    }
  }
}

TEST(BvhVsBrute, InvalidRaysMissWithoutTraversal) {
  const SceneGeometry g = mixed_spheres_and_triangles(50, 200, 3);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<Ray> invalid(7);
  invalid[0].org = {nan, 0.0f, 0.0f};
  invalid[1].dir = {0.0f, 0.0f, 0.0f};
  invalid[2].dir = {kInf, 0.0f, 0.0f};
  invalid[3].tmin = -1.0f;
  invalid[4].tmin = 2.0f, invalid[4].tmax = 1.0f;
  invalid[5].tmax = nan;
  invalid[6].tmin = kInf;
  for (const std::unique_ptr<Backend>& backend : {make_brute_backend(), make_bvh_backend(), make_wide_backend()}) {
    backend->build(g);
    QueryStats stats;
    for (const Ray& ray : invalid) {
      Hit hit;
      hit.geom_id = 5;  // must be reset
      EXPECT_FALSE(backend->intersect(ray, hit, &stats)) << backend->name() << " " << describe(ray);
      EXPECT_FALSE(hit.found());
      EXPECT_FALSE(backend->occluded(ray, &stats)) << backend->name() << " " << describe(ray);
    }
    EXPECT_EQ(stats.nodes_visited, 0u) << backend->name();
    EXPECT_EQ(stats.primitives_tested, 0u) << backend->name();
  }
}

}  // namespace
}  // namespace twinray
