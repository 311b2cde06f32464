// The crosscheck classifier: identical hits, edge ambiguities, ties and genuine mismatches.

#include "harness/crosscheck/hit_comparison.h"

#include <gtest/gtest.h>

#include <limits>

namespace twinray::crosscheck {
namespace {

// Two unit right triangles sharing the diagonal edge of the unit square in z = 0 (geom 0), and a
// second copy of the square at z = 0 (geom 1) for ties; a sphere (geom 2) far away.
SceneGeometry square_scene() {
  SceneGeometry g;
  TriangleMesh m;
  m.geom_id = 0;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.indices = {{0, 1, 2}, {0, 2, 3}};
  g.meshes.push_back(m);
  m.geom_id = 1;
  g.meshes.push_back(m);
  g.spheres.push_back({2, {10.0f, 0.0f, 0.0f}, 1.0f});
  return g;
}

Hit triangle_hit(std::uint32_t geom, std::uint32_t prim, float t, float u, float v) {
  Hit h;
  h.geom_id = geom;
  h.prim_id = prim;
  h.t = t;
  h.u = u;
  h.v = v;
  h.ng = {0, 0, 1};
  return h;
}

struct Case {
  Ray ray;
  Hit a, b;
};

PairComparison run(const GeometryIndex& index, const std::vector<Case>& cases) {
  std::vector<Ray> rays;
  std::vector<Hit> a, b;
  for (const Case& c : cases) {
    rays.push_back(c.ray);
    a.push_back(c.a);
    b.push_back(c.b);
  }
  return compare(index, rays, a, b, {}, {});
}

Ray down_at(float x, float y) {
  Ray r;
  r.org = {x, y, 1.0f};
  r.dir = {0, 0, -1};
  return r;
}

TEST(HitComparison, IdenticalWhenSamePrimitiveAndCloseT) {
  const SceneGeometry g = square_scene();
  const GeometryIndex index(g);
  const PairComparison c = run(index, {{down_at(0.7f, 0.2f), triangle_hit(0, 0, 1.0f, 0.5f, 0.2f),
                                        triangle_hit(0, 0, 1.0f + 3e-7f, 0.5f, 0.2f)},
                                       {down_at(5, 5), Hit{}, Hit{}}});
  EXPECT_EQ(c.identical, 2u);
  EXPECT_EQ(c.genuine + c.edge + c.tie, 0u);
  EXPECT_NEAR(c.max_rel_t_diff, 3e-7, 1e-7);
}

// A hit reported at t = +inf (a "no hit yet" value left in place) is nowhere: the relative t tolerance must
// not let it agree with the real crossing (1e-4 * inf is inf), nor make it look like the end of the interval.
TEST(HitComparison, InfiniteTNeverAgreesWithAFiniteOne) {
  const SceneGeometry g = square_scene();
  const GeometryIndex index(g);
  // Oblique, so that every coordinate of the point at t = +inf is infinite (and its tolerance with it).
  Ray ray = down_at(0.6f, 0.1f);
  ray.dir = {0.1f, 0.1f, -1.0f};
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(t_agrees(index, ray, inf, 1.0f));
  EXPECT_FALSE(t_agrees(index, ray, 1.0f, inf));
  EXPECT_FALSE(hit_is_ambiguous(index, ray, triangle_hit(0, 0, inf, 0.5f, 0.2f)));
  const PairComparison c =
      run(index, {{ray, triangle_hit(0, 0, inf, 0.5f, 0.2f), triangle_hit(0, 0, 1.0f, 0.5f, 0.2f)}});
  EXPECT_EQ(c.identical, 0u);
  EXPECT_EQ(c.genuine, 1u);
}

TEST(HitComparison, NeighbourAcrossSharedEdgeIsEdge) {
  const SceneGeometry g = square_scene();
  const GeometryIndex index(g);
  // (0.5, 0.5) lies on the shared diagonal p0-p2: triangle 0 sees it with weight 0 on its p1, triangle 1
  // (vertices p0, p2, p3) with weight 0 on its third vertex.
  const Hit a = triangle_hit(0, 0, 1.0f, 0.0f, 0.5f);   // b1 = 0: on edge p0-p2
  const Hit b = triangle_hit(0, 1, 1.0f, 0.5f, 0.0f);   // b2 = 0: on edge p0-p2 of triangle 1
  const PairComparison c = run(index, {{down_at(0.5f, 0.5f), a, b}});
  EXPECT_EQ(c.edge, 1u);
  EXPECT_EQ(c.genuine, 0u);
}

TEST(HitComparison, MissNextToEdgeIsEdgeButMissInTheMiddleIsGenuine) {
  const SceneGeometry g = square_scene();
  const GeometryIndex index(g);
  const PairComparison c = run(index, {{down_at(1.0f, 0.3f), triangle_hit(0, 0, 1.0f, 0.7f, 0.3f), Hit{}},
                                       {down_at(0.7f, 0.2f), triangle_hit(0, 0, 1.0f, 0.5f, 0.2f), Hit{}}});
  EXPECT_EQ(c.edge, 1u);
  EXPECT_EQ(c.genuine, 1u);
  ASSERT_EQ(c.examples.size(), 1u);
  EXPECT_EQ(c.examples[0].ray_index, 1u);
}

TEST(HitComparison, CoincidentDuplicateIsTie) {
  const SceneGeometry g = square_scene();
  const GeometryIndex index(g);
  const PairComparison c =
      run(index, {{down_at(0.7f, 0.2f), triangle_hit(0, 0, 1.0f, 0.5f, 0.2f), triangle_hit(1, 0, 1.0f, 0.5f, 0.2f)}});
  EXPECT_EQ(c.tie, 1u);
  EXPECT_EQ(c.genuine, 0u);
}

TEST(HitComparison, DifferentDepthIsGenuine) {
  const SceneGeometry g = square_scene();
  const GeometryIndex index(g);
  const PairComparison c =
      run(index, {{down_at(0.7f, 0.2f), triangle_hit(0, 0, 1.0f, 0.5f, 0.2f), triangle_hit(1, 0, 1.5f, 0.5f, 0.2f)},
                  {down_at(0.7f, 0.2f), triangle_hit(0, 0, 1.0f, 0.5f, 0.2f), triangle_hit(0, 0, 1.01f, 0.5f, 0.2f)}});
  EXPECT_EQ(c.genuine, 2u);
  EXPECT_EQ(c.identical, 0u);
}

TEST(HitComparison, GrazingSphereIsEdgeHeadOnIsGenuine) {
  const SceneGeometry g = square_scene();
  const GeometryIndex index(g);
  Ray graze;
  graze.org = {10.0f, 1.0f, -5.0f};  // tangent to the sphere at (10, 1, 0)
  graze.dir = {0, 0, 1};
  Hit hs;
  hs.geom_id = 2;
  hs.prim_id = 0;
  hs.t = 5.0f;
  hs.ng = {0, 1, 0};
  Ray head_on;
  head_on.org = {10.0f, 0.0f, -5.0f};
  head_on.dir = {0, 0, 1};
  Hit hh = hs;
  hh.t = 4.0f;
  const PairComparison c = run(index, {{graze, hs, Hit{}}, {head_on, hh, Hit{}}});
  EXPECT_EQ(c.edge, 1u);
  EXPECT_EQ(c.genuine, 1u);
}

TEST(HitComparison, OcclusionDisagreementsAreClassified) {
  const SceneGeometry g = square_scene();
  const GeometryIndex index(g);
  const std::vector<Ray> rays = {down_at(0.7f, 0.2f), down_at(1.0f, 0.3f)};
  const std::vector<Hit> a = {triangle_hit(0, 0, 1.0f, 0.5f, 0.2f), triangle_hit(0, 0, 1.0f, 0.7f, 0.3f)};
  const std::vector<Hit> b = a;
  const std::vector<std::uint8_t> oa = {1, 1}, ob = {0, 0};
  const PairComparison c = compare(index, rays, a, b, oa, ob);
  EXPECT_EQ(c.identical, 2u);
  EXPECT_EQ(c.occlusion_genuine, 1u);
  EXPECT_EQ(c.occlusion_edge, 1u);
}

}  // namespace
}  // namespace twinray::crosscheck
