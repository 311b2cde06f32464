// The arbiter (harness/arbiter/arbiter.h): planted wrong answers are ruled wrong, with the right reason;
// legitimate differences at edges, silhouettes, interval ends and ties are ruled right; watertightness and
// tie claims change exactly the rulings they should.

#include "harness/arbiter/arbiter.h"
#include "core/scene/procedural.h"
#include "ray_test_util.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>

namespace twinray::arbiter {
namespace {

using test::make_ray;

constexpr BackendTraits kWatertight{.counts_traversal = false, .honours_ties = true, .watertight = true};
constexpr BackendTraits kLoose{.counts_traversal = false, .honours_ties = false, .watertight = false};

TriangleMesh unit_square(std::uint32_t geom_id, float z) {
  TriangleMesh m;
  m.geom_id = geom_id;
  m.positions = {{0, 0, z}, {1, 0, z}, {1, 1, z}, {0, 1, z}};
  m.indices = {{0, 1, 2}, {0, 2, 3}};  // sharing the diagonal (0,0)-(1,1); triangle 1 is the half y > x
  m.positions.reserve(5);
  return m;
}

// geom 0: the unit square at z = 0; geom 1: the same square at z = -1; geom 2: a sphere away from both.
SceneGeometry layered_scene() {
  SceneGeometry g;
  g.meshes.push_back(unit_square(0, 0.0f));
  g.meshes.push_back(unit_square(1, -1.0f));
  g.spheres.push_back({2, {5.0f, 0.5f, 0.0f}, 0.5f});
  return g;
}

Hit hit_on(std::uint32_t geom, std::uint32_t prim, float t) {
  Hit h;
  h.geom_id = geom;
  h.prim_id = prim;
  h.t = t;
  return h;
}

const glm::vec3 kDown{0.0f, 0.0f, -1.0f};

TEST(Arbiter, TheExactAnswerIsRightAndPlantedErrorsAreWrong) {
  const SceneGeometry g = layered_scene();
  const Arbiter arbiter(g);
  const Ray ray = make_ray({0.25f, 0.75f, 1.0f}, kDown);
  const Hit exact = arbiter.exact_closest(ray);
  ASSERT_TRUE(exact.found());
  EXPECT_EQ(exact.geom_id, 0u);
  EXPECT_EQ(exact.prim_id, 1u);
  EXPECT_EQ(exact.t, 1.0f);

  const Ruling agrees = arbiter.rule_closest(ray, exact, kWatertight);
  EXPECT_TRUE(agrees.right);
  EXPECT_EQ(agrees.reason, Reason::Agrees);
  EXPECT_EQ(agrees.t_rel_error, 0.0);
  // A few ulps of t are right; 1% is not.
  EXPECT_TRUE(arbiter.rule_closest(ray, hit_on(0, 1, std::nextafter(1.0f, 2.0f)), kWatertight).right);
  const Ruling t_off = arbiter.rule_closest(ray, hit_on(0, 1, 1.01f), kWatertight);
  EXPECT_FALSE(t_off.right);
  EXPECT_EQ(t_off.reason, Reason::TOff);
  EXPECT_NEAR(t_off.t_rel_error, 0.01, 1e-6);
  // The square behind, while the front one is crossed in its middle.
  const Ruling behind = arbiter.rule_closest(ray, hit_on(1, 1, 2.0f), kLoose);
  EXPECT_FALSE(behind.right);
  EXPECT_EQ(behind.reason, Reason::WrongPrimitive);
  // A miss, and no occlusion.
  EXPECT_EQ(arbiter.rule_closest(ray, Hit{}, kLoose).reason, Reason::MissedHit);
  EXPECT_EQ(arbiter.rule_occluded(ray, false, kLoose).reason, Reason::MissedHit);
  EXPECT_TRUE(arbiter.rule_occluded(ray, true, kLoose).right);
  // A primitive the ray does not come near.
  EXPECT_EQ(arbiter.rule_closest(ray, hit_on(2, 0, 1.0f), kLoose).reason, Reason::HitNotThere);
  // A t outside [tmin, tmax].
  EXPECT_EQ(arbiter.rule_closest(make_ray({0.25f, 0.75f, 1.0f}, kDown, 0.0f, 0.5f), hit_on(0, 1, 1.0f), kLoose).reason,
            Reason::OutsideInterval);
  // Where the ray meets nothing at all.
  const Ray nowhere = make_ray({3.0f, 3.0f, 1.0f}, kDown);
  EXPECT_EQ(arbiter.rule_closest(nowhere, hit_on(0, 0, 1.0f), kLoose).reason, Reason::HitNotThere);
  EXPECT_EQ(arbiter.rule_occluded(nowhere, true, kLoose).reason, Reason::HitNotThere);
  EXPECT_TRUE(arbiter.rule_occluded(nowhere, false, kLoose).right);
  // An invalid ray may only miss.
  const Ray invalid = make_ray({0.25f, 0.75f, 1.0f}, glm::vec3(0.0f));
  EXPECT_FALSE(arbiter.rule_closest(invalid, hit_on(0, 1, 1.0f), kLoose).right);
  EXPECT_TRUE(arbiter.rule_closest(invalid, Hit{}, kLoose).right);
}

TEST(Arbiter, EdgesSharedByTwoTrianglesGoEitherWayButMayNotLeakForWatertightClaims) {
  const SceneGeometry g = layered_scene();
  const Arbiter arbiter(g);
  const Ray diagonal = make_ray({0.5f, 0.5f, 1.0f}, kDown);  // exactly through the shared diagonal
  const Hit exact = arbiter.exact_closest(diagonal);
  ASSERT_TRUE(exact.found());
  ASSERT_EQ(exact.geom_id, 0u);
  const std::uint32_t other = 1u - exact.prim_id;
  for (const BackendTraits& traits : {kWatertight, kLoose}) {
    const Ruling neighbour = arbiter.rule_closest(diagonal, hit_on(0, other, 1.0f), traits);
    EXPECT_TRUE(neighbour.right) << neighbour.detail;
    EXPECT_EQ(neighbour.reason, Reason::Edge);
  }
  // Losing the crossing there is a hole: wrong for a backend that claims watertightness.
  EXPECT_EQ(arbiter.rule_closest(diagonal, Hit{}, kWatertight).reason, Reason::MissedHit);
  EXPECT_EQ(arbiter.rule_occluded(diagonal, false, kWatertight).reason, Reason::MissedHit);
  const Ruling leak = arbiter.rule_closest(diagonal, Hit{}, kLoose);
  EXPECT_TRUE(leak.right);
  EXPECT_EQ(leak.reason, Reason::Edge);
  // The square's outer boundary is an edge the ray can leave the surface through: missing it is right even
  // for a watertight backend, and so is hitting the triangle from just outside.
  const Ray boundary = make_ray({1.0f, 0.5f, 1.0f}, kDown);
  EXPECT_TRUE(arbiter.rule_closest(boundary, Hit{}, kWatertight).right);
  EXPECT_TRUE(arbiter.rule_occluded(boundary, false, kWatertight).right);
  const Ray just_outside = make_ray({1.0f + 0x1p-20f, 0.5f, 1.0f}, kDown);
  EXPECT_FALSE(arbiter.exact_closest(just_outside).found() && arbiter.exact_closest(just_outside).geom_id == 0);
  const Ruling grazed = arbiter.rule_closest(just_outside, hit_on(0, 0, 1.0f), kWatertight);
  EXPECT_TRUE(grazed.right) << grazed.detail;
  EXPECT_EQ(grazed.reason, Reason::Edge);
  // Far outside, the same answer is a hit that is not there.
  EXPECT_EQ(arbiter.rule_closest(make_ray({1.01f, 0.5f, 1.0f}, kDown), hit_on(0, 0, 1.0f), kWatertight).reason,
            Reason::HitNotThere);
}

// A ray from the center of a closed tessellated sphere exactly through a vertex: any triangle of the fan is a
// right answer, but a miss is a leak.
TEST(Arbiter, RaysThroughAVertexOfAClosedMesh) {
  const SceneGeometry g = tessellated_sphere(glm::vec3(0.0f), 1.0f, 2);
  const Arbiter arbiter(g);
  const TriangleMesh& mesh = g.meshes[0];
  int checked = 0;
  for (std::uint32_t v = 0; v < 40; ++v) {
    const Ray ray = make_ray(glm::vec3(0.0f), mesh.positions[v]);
    const Hit exact = arbiter.exact_closest(ray);
    ASSERT_TRUE(exact.found());
    EXPECT_EQ(arbiter.rule_closest(ray, Hit{}, kWatertight).reason, Reason::MissedHit);
    for (std::uint32_t k = 0; k < mesh.indices.size(); ++k) {
      const glm::uvec3& tri = mesh.indices[k];
      if (k == exact.prim_id || (tri.x != v && tri.y != v && tri.z != v)) continue;
      const Ruling r = arbiter.rule_closest(ray, hit_on(0, k, exact.t), kWatertight);
      EXPECT_TRUE(r.right) << r.detail;
      EXPECT_EQ(r.reason, Reason::Edge);
      ++checked;
    }
  }
  EXPECT_GT(checked, 150);
}

TEST(Arbiter, IntervalEndsAndSphereSilhouettes) {
  const SceneGeometry g = layered_scene();
  const Arbiter arbiter(g);
  // tmax a hair before the square: the exact ray stops short of it, but counting it is right.
  const Ray short_ray = make_ray({0.25f, 0.75f, 1.0f}, kDown, 0.0f, 1.0f - 0x1p-20f);
  EXPECT_FALSE(arbiter.exact_occluded(short_ray));
  const Ruling occluded = arbiter.rule_occluded(short_ray, true, kWatertight);
  EXPECT_TRUE(occluded.right);
  EXPECT_EQ(occluded.reason, Reason::IntervalEnd);
  const Ruling closest = arbiter.rule_closest(short_ray, hit_on(0, 1, short_ray.tmax), kWatertight);
  EXPECT_TRUE(closest.right) << closest.detail;
  EXPECT_EQ(closest.reason, Reason::IntervalEnd);
  // And with tmax a hair beyond it, not counting it is right too.
  const Ray long_ray = make_ray({0.25f, 0.75f, 1.0f}, kDown, 0.0f, 1.0f + 0x1p-20f);
  EXPECT_EQ(arbiter.rule_occluded(long_ray, false, kWatertight).reason, Reason::IntervalEnd);
  // A sphere grazed from just outside its silhouette: a hit is right...
  const Ray outside = make_ray({5.5f + 0x1p-21f, 0.5f, 1.0f}, kDown);
  EXPECT_FALSE(arbiter.exact_occluded(outside));
  const Ruling graze = arbiter.rule_closest(outside, hit_on(2, 0, 1.0f), kWatertight);
  EXPECT_TRUE(graze.right) << graze.detail;
  EXPECT_EQ(graze.reason, Reason::Edge);
  // ... and so is a miss from just inside it; but not a miss through the middle.
  const Ray inside = make_ray({5.5f - 0x1p-21f, 0.5f, 1.0f}, kDown);
  ASSERT_TRUE(arbiter.exact_occluded(inside));
  EXPECT_TRUE(arbiter.rule_closest(inside, Hit{}, kWatertight).right);
  EXPECT_EQ(arbiter.rule_closest(make_ray({5.0f, 0.5f, 1.0f}, kDown), Hit{}, kWatertight).reason, Reason::MissedHit);
  // The sphere's far side while the near side is in the interval: t-off (of the near root).
  EXPECT_EQ(arbiter.rule_closest(make_ray({5.0f, 0.5f, 1.0f}, kDown), hit_on(2, 0, 1.5f), kWatertight).reason,
            Reason::TOff);
}

TEST(Arbiter, TiesAreJudgedOnlyForBackendsThatClaimThem) {
  SceneGeometry g;
  g.meshes.push_back(unit_square(0, 0.0f));
  g.meshes.push_back(unit_square(1, 0.0f));  // the same square again: every crossing is a tie
  const Arbiter arbiter(g);
  const Ray ray = make_ray({0.25f, 0.75f, 1.0f}, kDown);
  const Hit exact = arbiter.exact_closest(ray);
  ASSERT_EQ(exact.geom_id, 0u);
  const Ruling claimed = arbiter.rule_closest(ray, hit_on(1, exact.prim_id, exact.t), kWatertight);
  EXPECT_FALSE(claimed.right);
  EXPECT_EQ(claimed.reason, Reason::TieBrokenWrongly);
  const Ruling not_claimed = arbiter.rule_closest(ray, hit_on(1, exact.prim_id, exact.t), kLoose);
  EXPECT_TRUE(not_claimed.right);
  EXPECT_EQ(not_claimed.reason, Reason::Tie);
  EXPECT_TRUE(is_wrong(Reason::TieBrokenWrongly) && !is_wrong(Reason::Tie));
}

}  // namespace
}  // namespace twinray::arbiter
