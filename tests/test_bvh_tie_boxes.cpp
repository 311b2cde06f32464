// The closest-hit traversal's tie boxes (bvh_traversal.inl, pop_closest): a popped box entered exactly at
// the best t so far must still be visited, since a primitive below it may tie at that t with a lower
// (geom_id, prim_id) (a rule that skips such boxes by a per-subtree minimum key was tried in the twelfth
// round and gained nothing: docs/bvh-backend.md). Adversarial scenes for the tie rule: the same coplanar
// tiles in three geometries, in different orders, so that every crossing is a tie at one rounded t between
// several geometries and primitives in different leaves, and the lowest key is sometimes found first and
// sometimes last; rays with their own interval and with tmin = tmax = the tie's t; rays whose origin lies
// on a tile's edge plane.

#include "backends/brute/brute_backend.h"
#include "backends/bvh/bvh_backend.h"
#include "core/sampling/rng.h"
#include "coplanar_tiles_test_util.h"
#include "ray_test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace twinray {
namespace {

// 150 coplanar tiles at z = 0.3 (overlapping), copied into geometries 2, 0 and 1: geometry 2 in tile order,
// geometry 0 reversed, geometry 1 rotated by a third, so each tile's three copies have different prim ids.
SceneGeometry tiles_in_three_geometries() {
  Rng rng(21, 0);
  const std::vector<glm::vec3> tiles = test::overlapping_tile_corners(rng, 150);
  const std::size_t n = tiles.size() / 3;
  SceneGeometry g;
  const std::uint32_t ids[] = {2, 0, 1};
  for (int copy = 0; copy < 3; ++copy) {
    TriangleMesh mesh;
    mesh.geom_id = ids[copy];
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = copy == 0 ? i : copy == 1 ? n - 1 - i : (i + n / 3) % n;
      const auto first = static_cast<std::uint32_t>(mesh.positions.size());
      for (int j = 0; j < 3; ++j) mesh.positions.push_back(tiles[3 * k + j]);
      mesh.indices.push_back({first, first + 1, first + 2});
    }
    mesh.positions.reserve(mesh.positions.size() + 1);
    g.meshes.push_back(mesh);
  }
  return g;
}

// Found or not alike, and then the same answer to the bit (the normal included).
bool same_hit(bool hit_a, const Hit& a, bool hit_b, const Hit& b) { return hit_a == hit_b && test::same_hit_bits(a, b); }

TEST(BvhTieBoxes, TiesAcrossGeometriesGoToTheLowestKey) {
  const SceneGeometry g = tiles_in_three_geometries();
  const std::unique_ptr<Backend> brute = make_brute_backend();
  brute->build(g);
  // Rays as they come, the same rays with tmin = tmax = their tie's t, and rays from a tile's edge (the
  // origin on the edge's line, lifted above the plane only along z) towards the tiles.
  std::vector<Ray> rays;
  Rng rng(22, 0);
  for (int i = 0; i < 1500; ++i) {
    Ray ray = test::ray_towards_tiles(rng);
    rays.push_back(ray);
    Hit hit;
    if (brute->intersect(ray, hit)) {
      ray.tmin = ray.tmax = hit.t;
      rays.push_back(ray);
    }
  }
  const TriangleMesh& mesh = g.meshes[0];
  for (std::size_t i = 0; i < mesh.indices.size(); ++i) {
    const glm::vec3 a = mesh.positions[mesh.indices[i][0]], b = mesh.positions[mesh.indices[i][1]];
    Ray ray = test::ray_towards_tiles(rng);
    ray.org = {0.5f * (a.x + b.x), a.y, 1.0f};  // above the edge a-b (both at y = c.y - 0.3)
    ray.dir = {0.0f, 0.0f, -1.0f};
    rays.push_back(ray);
  }
  std::vector<Hit> expected(rays.size());
  std::vector<bool> expected_hit(rays.size());
  std::size_t hits = 0, lowest_not_first = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    expected_hit[i] = brute->intersect(rays[i], expected[i]);
    hits += expected_hit[i] ? 1 : 0;
    lowest_not_first += expected_hit[i] && expected[i].geom_id != 2 ? 1 : 0;
  }
  ASSERT_GT(hits, rays.size() / 2);
  ASSERT_GT(lowest_not_first, hits / 2);  // the winner is mostly not in the first geometry built

  BvhBuildOptions one_per_leaf;
  one_per_leaf.max_leaf_size = 1;
  for (const Isa isa : runnable_isas()) {
    for (const BvhBuildOptions& options : {BvhBuildOptions{}, one_per_leaf}) {
      BvhBackend bvh(options, isa);
      bvh.build(g);
      SCOPED_TRACE(std::string(to_string(isa)) + " max_leaf_size " + std::to_string(options.max_leaf_size));
      std::size_t differ = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        Hit hit;
        const bool found = bvh.intersect(rays[i], hit);
        differ += same_hit(expected_hit[i], expected[i], found, hit) ? 0 : 1;
        std::vector<BvhVisit> visits;
        Hit traced;
        const bool traced_found = bvh.intersect_traced(rays[i], traced, visits);
        differ += same_hit(expected_hit[i], expected[i], traced_found, traced) ? 0 : 1;
      }
      EXPECT_EQ(differ, 0u);
    }
  }
}

}  // namespace
}  // namespace twinray
