// The bvh and bvh8 backends' batch queries trace rays in the Morton order of their origins (backends/bvh/ray_order.h):
// the answers must be exactly those of single-ray calls, slot for slot, with the same statistics, invalid
// rays included; and the order must be a deterministic permutation that follows the curve.

#include "backends/bvh/bvh_backend.h"
#include "backends/bvh/ray_order.h"
#include "backends/wide/wide_backend.h"
#include "core/sampling/rng.h"
#include "core/scene/procedural.h"
#include "ray_test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <vector>

namespace twinray {
namespace {

using test::same_bits;

std::vector<Ray> rays_with_invalid_slots(std::size_t n, std::uint64_t seed) {
  Rng rng(seed, 0);
  const auto uniform = [&] { return 3.0f * rng.next_float() - 1.5f; };
  std::vector<Ray> rays(n);
  for (std::size_t i = 0; i < n; ++i) {
    Ray& r = rays[i];
    r.org = {uniform(), uniform(), uniform()};
    r.dir = glm::vec3(uniform(), uniform(), uniform()) - r.org;
    if (r.dir == glm::vec3(0.0f)) r.dir.x = 1.0f;
    if (i % 97 == 0) r.org.y = std::numeric_limits<float>::quiet_NaN();  // invalid: a miss, in its own slot
    if (i % 89 == 0) r.tmax = 0.5f * rng.next_float();
  }
  return rays;
}

TEST(BvhBatch, BatchAnswersEqualSingleRayAnswersSlotForSlot) {
  const SceneGeometry geometry = mixed_spheres_and_triangles(50, 2000, 3);
  for (const std::unique_ptr<Backend>& tree : {make_bvh_backend(), make_wide_backend()}) {
    SCOPED_TRACE(std::string(tree->name()));
    Backend& bvh = *tree;
    bvh.build(geometry);
    const std::vector<Ray> rays = rays_with_invalid_slots(20000, 11);

    std::vector<Hit> batch(rays.size());
    std::vector<std::uint8_t> batch_occluded(rays.size());
    QueryStats batch_stats, single_stats;
    bvh.intersect(rays, batch, &batch_stats);
    bvh.occluded(rays, batch_occluded, &batch_stats);

    std::size_t hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      Hit h;
      const bool found = bvh.intersect(rays[i], h, &single_stats);
      const bool occluded = bvh.occluded(rays[i], &single_stats);
      hits += found ? 1 : 0;
      ASSERT_EQ(batch[i].found(), found) << "ray " << i;
      ASSERT_EQ(batch_occluded[i] != 0, occluded) << "ray " << i;
      if (!found) continue;
      EXPECT_EQ(batch[i].geom_id, h.geom_id) << "ray " << i;
      EXPECT_EQ(batch[i].prim_id, h.prim_id) << "ray " << i;
      EXPECT_TRUE(same_bits(batch[i].t, h.t) && same_bits(batch[i].u, h.u) && same_bits(batch[i].v, h.v) &&
                  same_bits(batch[i].ng.x, h.ng.x) && same_bits(batch[i].ng.y, h.ng.y) && same_bits(batch[i].ng.z, h.ng.z))
          << "ray " << i;
    }
    EXPECT_GT(hits, rays.size() / 4);  // a test that hits nothing proves nothing
    EXPECT_EQ(batch_stats.queries, single_stats.queries);
    EXPECT_EQ(batch_stats.nodes_visited, single_stats.nodes_visited);
    EXPECT_EQ(batch_stats.primitives_tested, single_stats.primitives_tested);
  }
}

TEST(BvhBatch, MortonOrderIsADeterministicPermutationAlongTheCurve) {
  const Bounds3 bounds{glm::vec3(-1.5f), glm::vec3(1.5f)};
  std::vector<Ray> rays = rays_with_invalid_slots(5000, 4);
  // Duplicated origins: ties keep the input order.
  for (std::size_t i = 0; i + 1 < rays.size(); i += 50) rays[i + 1].org = rays[i].org;
  const std::vector<std::uint32_t> order = morton_ray_order(rays, bounds);
  EXPECT_EQ(order, morton_ray_order(rays, bounds));

  std::vector<std::uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (std::uint32_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i) << "not a permutation";

  // Along a Z-order curve, consecutive origins in the same octant of the bounds are never followed by one
  // in a lower octant: the octant (top 3 bits of the code) is non-decreasing.
  // (A NaN component quantizes to 0, and `>=` is false for NaN.)
  const auto octant = [&](const Ray& r) {
    return (r.org.x >= 0.0f ? 4 : 0) | (r.org.y >= 0.0f ? 2 : 0) | (r.org.z >= 0.0f ? 1 : 0);
  };
  for (std::size_t k = 1; k < order.size(); ++k) {
    ASSERT_LE(octant(rays[order[k - 1]]), octant(rays[order[k]])) << "position " << k;
    if (rays[order[k]].org == rays[order[k - 1]].org) {
      EXPECT_LT(order[k - 1], order[k]) << "ties keep the input order";
    }
  }
}

}  // namespace
}  // namespace twinray
