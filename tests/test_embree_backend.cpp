// The Embree backends (`embree`, robust; `embree-fast`) on small procedural scenes with known answers.

#include "backends/embree/embree_backend.h"
#include "core/intersect/sphere_robust.h"
#include "core/sampling/rng.h"
#include "core/util/fp_mode.h"
#include "ray_test_util.h"

#include <embree3/rtcore.h>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

namespace twinray {
namespace {

using test::kInf;
using test::kNaN;
using test::make_ray;

// A mesh as the loaders make it: with the spare vertex capacity Embree's 16-byte loads need.
TriangleMesh make_mesh(std::uint32_t geom_id, const std::vector<glm::vec3>& positions,
                       const std::vector<glm::uvec3>& indices) {
  TriangleMesh m;
  m.geom_id = geom_id;
  m.positions.reserve(positions.size() + 1);
  m.positions.assign(positions.begin(), positions.end());
  m.indices = indices;
  return m;
}

// n x n unit cells in the plane z = `z`, spanning [0,n]^2, two counter-clockwise (+z facing) triangles per
// cell: cell (i, j) owns primitives 2(j n + i) (lower right half) and 2(j n + i) + 1 (upper left half).
TriangleMesh make_grid(std::uint32_t geom_id, int n, float z) {
  std::vector<glm::vec3> p;
  std::vector<glm::uvec3> idx;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) p.emplace_back(static_cast<float>(i), static_cast<float>(j), z);
  const auto vid = [n](int i, int j) { return static_cast<unsigned>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      idx.emplace_back(vid(i, j), vid(i + 1, j), vid(i + 1, j + 1));
      idx.emplace_back(vid(i, j), vid(i + 1, j + 1), vid(i, j + 1));
    }
  return make_mesh(geom_id, p, idx);
}

Sphere make_sphere(std::uint32_t geom_id, glm::vec3 center, float radius) {
  Sphere s;
  s.geom_id = geom_id;
  s.center = center;
  s.radius = radius;
  return s;
}

class EmbreeBackendTest : public ::testing::TestWithParam<bool> {
 protected:
  std::unique_ptr<Backend> build(const SceneGeometry& g) {
    auto backend = make_embree_backend(GetParam());
    backend->build(g);
    return backend;
  }
  ScopedFlushDenormals ftz_;
};

TEST_P(EmbreeBackendTest, NameAndTraits) {
  auto backend = make_embree_backend(GetParam());
  EXPECT_EQ(backend->name(), GetParam() ? "embree" : "embree-fast");
  const BackendTraits t = backend->traits();
  EXPECT_FALSE(t.counts_traversal);
  EXPECT_FALSE(t.honours_ties);
  EXPECT_EQ(t.watertight, GetParam());
}

// Embree rounds t its own way, and differently per ISA: its AVX2 kernels return 1 - 1 ulp where the exact
// answer is 1 (other kernels have returned it exactly). Two ulps of the answer is the tolerance.
void expect_t(float t, float exact) { EXPECT_NEAR(t, exact, 2.0f * (std::nextafter(exact, 2.0f * exact) - exact)); }

TEST_P(EmbreeBackendTest, TriangleHitReportsTUVAndOurNormal) {
  SceneGeometry g;
  g.meshes.push_back(make_mesh(0, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}));
  auto backend = build(g);

  // The hit point (u, v, 0) = (1-u-v) p0 + u p1 + v p2, so (u, v) are the point's x and y.
  Hit hit;
  ASSERT_TRUE(backend->intersect(make_ray({0.25f, 0.5f, 1.0f}, {0, 0, -1}), hit));
  expect_t(hit.t, 1.0f);
  EXPECT_NEAR(hit.u, 0.25f, 1e-6f);
  EXPECT_NEAR(hit.v, 0.5f, 1e-6f);
  EXPECT_EQ(hit.geom_id, 0u);
  EXPECT_EQ(hit.prim_id, 0u);
  EXPECT_EQ(hit.ng, glm::vec3(0, 0, 1));

  // From behind: the normal is the counter-clockwise front, never flipped toward the ray. A direction of
  // length 2 halves t (t is in units of |dir|).
  ASSERT_TRUE(backend->intersect(make_ray({0.125f, 0.25f, -3.0f}, {0, 0, 2}), hit));
  expect_t(hit.t, 1.5f);
  EXPECT_NEAR(hit.u, 0.125f, 1e-6f);
  EXPECT_NEAR(hit.v, 0.25f, 1e-6f);
  EXPECT_EQ(hit.ng, glm::vec3(0, 0, 1));

  EXPECT_FALSE(backend->intersect(make_ray({0.75f, 0.75f, 1.0f}, {0, 0, -1}), hit));  // outside the hypotenuse
  EXPECT_FALSE(hit.found());
}

TEST_P(EmbreeBackendTest, BarycentricsReconstructTheHitPointOnAGeneralTriangle) {
  const glm::vec3 p0{-1.3f, 0.2f, 2.0f}, p1{2.1f, -0.7f, 1.1f}, p2{0.4f, 1.9f, -0.6f};
  SceneGeometry g;
  g.meshes.push_back(make_mesh(0, {p0, p1, p2}, {{0, 1, 2}}));
  auto backend = build(g);
  const glm::vec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
  Rng rng(7, 1);
  for (int k = 0; k < 200; ++k) {
    const float a = rng.next_float(), b = rng.next_float() * (1.0f - a);
    const glm::vec3 target = (1.0f - a - b) * p0 + a * p1 + b * p2;
    const glm::vec3 org = target + glm::vec3(0.3f, -0.2f, 4.0f) * (0.5f + rng.next_float());
    Hit hit;
    ASSERT_TRUE(backend->intersect(make_ray(org, target - org), hit)) << k;
    const glm::vec3 on_ray = org + hit.t * (target - org);
    const glm::vec3 from_uv = (1.0f - hit.u - hit.v) * p0 + hit.u * p1 + hit.v * p2;
    // Both points are the same surface point up to float rounding of coordinates of magnitude ~5.
    EXPECT_LT(glm::length(on_ray - from_uv), 1e-5f) << k;
    EXPECT_NEAR(hit.t, 1.0f, 1e-5f) << k;
    EXPECT_LT(glm::length(hit.ng - n), 1e-6f) << k;
  }
}

TEST_P(EmbreeBackendTest, GridPrimitiveIdsAndGeometryIdsMatchTheScene) {
  SceneGeometry g;
  constexpr int kN = 16;
  g.meshes.push_back(make_grid(5, kN, 0.0f));   // attached under id 5: Embree's ids are the scene's
  g.meshes.push_back(make_grid(2, kN, -1.0f));  // hidden below
  auto backend = build(g);
  for (int j = 0; j < kN; ++j)
    for (int i = 0; i < kN; ++i) {
      const auto cell = static_cast<std::uint32_t>(2 * (j * kN + i));
      const auto x = static_cast<float>(i), y = static_cast<float>(j);
      Hit hit;
      // Lower right half (x - i > y - j) is the cell's first triangle, upper left its second.
      ASSERT_TRUE(backend->intersect(make_ray({x + 0.75f, y + 0.25f, 3.0f}, {0, 0, -1}), hit));
      EXPECT_EQ(hit.geom_id, 5u);
      EXPECT_EQ(hit.prim_id, cell);
      expect_t(hit.t, 3.0f);
      ASSERT_TRUE(backend->intersect(make_ray({x + 0.25f, y + 0.75f, 3.0f}, {0, 0, -1}), hit));
      EXPECT_EQ(hit.prim_id, cell + 1);
      // Between the planes, looking down: only the lower grid.
      ASSERT_TRUE(backend->intersect(make_ray({x + 0.5f, y + 0.3f, -0.5f}, {0, 0, -1}), hit));
      EXPECT_EQ(hit.geom_id, 2u);
      expect_t(hit.t, 0.5f);
    }
}

TEST_P(EmbreeBackendTest, SphereHitsUseTheSharedRobustRoutine) {
  SceneGeometry g;
  g.spheres.push_back(make_sphere(3, {0, 0, -5}, 1.0f));
  auto backend = build(g);

  Hit hit;
  ASSERT_TRUE(backend->intersect(make_ray({0, 0, 0}, {0, 0, -1}), hit));
  EXPECT_EQ(hit.t, 4.0f);
  EXPECT_EQ(hit.geom_id, 3u);
  EXPECT_EQ(hit.prim_id, 0u);
  EXPECT_EQ(hit.ng, glm::vec3(0, 0, 1));  // outward

  // From inside the sphere: the exit point, normal still outward.
  ASSERT_TRUE(backend->intersect(make_ray({0, 0, -5}, {0, 1, 0}), hit));
  EXPECT_EQ(hit.t, 1.0f);
  EXPECT_EQ(hit.ng, glm::vec3(0, 1, 0));
  EXPECT_EQ(hit.v, 0.0f);  // theta from +Y

  // An oblique ray: t, normal and (u, v) are bit-identical to the shared routine's.
  const glm::vec3 org{0.3f, -0.2f, 1.0f};
  const Ray r = make_ray(org, glm::normalize(glm::vec3(0.2f, 0.3f, -4.2f) - org));
  ASSERT_TRUE(backend->intersect(r, hit));
  float t = 0.0f;
  ASSERT_TRUE(intersect_sphere(r.org, r.dir, g.spheres[0].center, 1.0f, r.tmin, r.tmax, t));
  glm::vec3 ng;
  float u = 0.0f, v = 0.0f;
  sphere_hit_attributes(r.org, r.dir, t, g.spheres[0].center, 1.0f, ng, u, v);
  EXPECT_EQ(hit.t, t);
  EXPECT_EQ(hit.ng, ng);
  EXPECT_EQ(hit.u, u);
  EXPECT_EQ(hit.v, v);

  EXPECT_FALSE(backend->intersect(make_ray({0, 0, 0}, {0, 0, 1}), hit));
  EXPECT_FALSE(backend->intersect(make_ray({0, 2.0f, 0}, {0, 0, -1}), hit));  // passes above
}

TEST_P(EmbreeBackendTest, InterleavedMeshAndSphereIdsAreTranslatedBack) {
  SceneGeometry g;
  g.meshes.push_back(make_mesh(0, {{-1, -1, -10}, {1, -1, -10}, {0, 1, -10}}, {{0, 1, 2}}));
  g.spheres.push_back(make_sphere(1, {5, 0, -10}, 1.0f));
  g.meshes.push_back(make_mesh(2, {{9, -1, -10}, {11, -1, -10}, {10, 1, -10}}, {{0, 1, 2}}));
  g.spheres.push_back(make_sphere(3, {15, 0, -10}, 1.0f));
  auto backend = build(g);
  for (std::uint32_t id = 0; id < 4; ++id) {
    Hit hit;
    ASSERT_TRUE(backend->intersect(make_ray({5.0f * static_cast<float>(id), 0, 0}, {0, 0, -1}), hit)) << id;
    EXPECT_EQ(hit.geom_id, id);
    EXPECT_EQ(hit.prim_id, 0u);
    expect_t(hit.t, id % 2 == 0 ? 10.0f : 9.0f);
  }
}

TEST_P(EmbreeBackendTest, IntervalIsHonoured) {
  SceneGeometry g;
  g.meshes.push_back(make_grid(0, 2, 0.0f));
  g.spheres.push_back(make_sphere(1, {1, 1, 5}, 1.0f));
  auto backend = build(g);
  Hit hit;
  // The grid at t = 10, the sphere at t = 4 (entry) and t = 6 (exit) on the way up.
  const glm::vec3 org{1.0f, 1.0f, -10.0f}, up{0, 0, 1};
  ASSERT_TRUE(backend->intersect(make_ray(org, up), hit));
  expect_t(hit.t, 10.0f);  // Embree's triangle t; the spheres below are ours, exact
  EXPECT_FALSE(backend->intersect(make_ray(org, up, 0.0f, 9.5f), hit));
  ASSERT_TRUE(backend->intersect(make_ray(org, up, 10.5f), hit));
  EXPECT_EQ(hit.t, 14.0f);
  ASSERT_TRUE(backend->intersect(make_ray(org, up, 14.5f), hit));
  EXPECT_EQ(hit.t, 16.0f);
  EXPECT_FALSE(backend->intersect(make_ray(org, up, 16.5f), hit));
  EXPECT_FALSE(backend->occluded(make_ray(org, up, 0.0f, 9.5f)));
  EXPECT_TRUE(backend->occluded(make_ray(org, up, 10.5f, 15.0f)));
}

// Debian's Embree aborts on such rays; the backend must report them as misses without passing them on.
TEST_P(EmbreeBackendTest, InvalidRaysAreMissesAndDoNotAbort) {
  SceneGeometry g;
  g.meshes.push_back(make_grid(0, 4, 0.0f));
  g.spheres.push_back(make_sphere(1, {2, 2, 0}, 1.0f));
  auto backend = build(g);
  const glm::vec3 org{2.0f, 2.0f, 5.0f}, down{0, 0, -1};
  const std::vector<Ray> invalid = {
      make_ray({kNaN, 2, 5}, down),          make_ray({2, kInf, 5}, down),
      make_ray(org, {0, kNaN, -1}),          make_ray(org, {0, 0, -kInf}),
      make_ray(org, {0, 0, 0}),              make_ray(org, down, -1.0f),
      make_ray(org, down, kNaN),             make_ray(org, down, 0.0f, kNaN),
      make_ray(org, down, 3.0f, 2.0f),       make_ray(org, down, kInf, kInf),
  };
  Hit valid_hit;
  ASSERT_TRUE(backend->intersect(make_ray(org, down), valid_hit));  // the valid version of each ray hits
  for (std::size_t k = 0; k < invalid.size(); ++k) {
    Hit hit;
    hit.geom_id = 42;  // stale content must be reset to a miss
    hit.t = 1.0f;
    EXPECT_FALSE(backend->intersect(invalid[k], hit)) << k;
    EXPECT_FALSE(hit.found()) << k;
    EXPECT_EQ(hit.t, kInf) << k;
    EXPECT_FALSE(backend->occluded(invalid[k])) << k;
  }
  // The batch paths filter them too, and keep valid rays in between working.
  std::vector<Ray> batch = invalid;
  batch.insert(batch.begin() + 3, make_ray(org, down));
  std::vector<Hit> hits(batch.size());
  std::vector<std::uint8_t> occ(batch.size(), 7);
  QueryStats stats;
  backend->intersect(batch, hits, &stats);
  backend->occluded(batch, occ, &stats);
  EXPECT_EQ(stats.queries, 2 * batch.size());
  for (std::size_t k = 0; k < batch.size(); ++k) {
    EXPECT_EQ(hits[k].found(), k == 3) << k;
    EXPECT_EQ(occ[k], k == 3 ? 1 : 0) << k;
  }
  EXPECT_EQ(hits[3].t, 4.0f);  // the sphere's top at z = 1
}

TEST_P(EmbreeBackendTest, TriangleOnlySceneBuildsNoSphereGeometry) {
  SceneGeometry g;
  g.meshes.push_back(make_grid(0, 8, 0.0f));
  auto backend = build(g);
  const BuildStats s = backend->build_stats();
  EXPECT_TRUE(s.built_triangles);
  EXPECT_FALSE(s.built_spheres);
  EXPECT_EQ(s.triangles, 128u);
  EXPECT_EQ(s.spheres, 0u);
  EXPECT_GT(s.memory_bytes, 0u);  // from the device memory monitor
  EXPECT_GE(s.build_seconds, 0.0);
}

TEST_P(EmbreeBackendTest, SphereOnlySceneBuildsNoTriangleGeometry) {
  SceneGeometry g;
  for (std::uint32_t k = 0; k < 10; ++k) g.spheres.push_back(make_sphere(k, {3.0f * static_cast<float>(k), 0, 0}, 1.0f));
  auto backend = build(g);
  const BuildStats s = backend->build_stats();
  EXPECT_FALSE(s.built_triangles);
  EXPECT_TRUE(s.built_spheres);
  EXPECT_EQ(s.triangles, 0u);
  EXPECT_EQ(s.spheres, 10u);
  EXPECT_GT(s.memory_bytes, 0u);
}

TEST_P(EmbreeBackendTest, EmptySceneMissesEverything) {
  SceneGeometry g;
  auto backend = build(g);
  Hit hit;
  EXPECT_FALSE(backend->intersect(make_ray({0, 0, 0}, {0, 0, -1}), hit));
  EXPECT_FALSE(backend->occluded(make_ray({0, 0, 0}, {0, 0, -1})));
  EXPECT_FALSE(backend->build_stats().built_triangles);
  EXPECT_FALSE(backend->build_stats().built_spheres);
}

TEST_P(EmbreeBackendTest, BuffersAreSharedUnlessTheTailPaddingIsMissing) {
  SceneGeometry g;
  g.meshes.push_back(make_grid(0, 2, 0.0f));  // padded by make_mesh
  TriangleMesh tight;
  tight.geom_id = 1;
  tight.positions = {{10, 0, 0}, {11, 0, 0}, {10, 1, 0}};
  tight.indices = {{0, 1, 2}};
  g.meshes.push_back(tight);
  g.meshes.back().positions.shrink_to_fit();
  ASSERT_EQ(g.meshes.back().positions.capacity(), g.meshes.back().positions.size()) << "the test needs no padding";
  auto backend = build(g);

  const EmbreeBuildReport* report = embree_build_report(*backend);
  ASSERT_NE(report, nullptr);
  EXPECT_EQ(report->shared_meshes, 1u);
  EXPECT_EQ(report->padded_mesh_copies, 1u);
  Hit hit;
  ASSERT_TRUE(backend->intersect(make_ray({10.25f, 0.25f, 1.0f}, {0, 0, -1}), hit));  // the copied mesh works
  EXPECT_EQ(hit.geom_id, 1u);
  EXPECT_NEAR(hit.u, 0.25f, 1e-6f);
}

// Random rays through a mixed scene: occluded() agrees with intersect(), and the batch paths return
// exactly what the single-ray paths return.
TEST_P(EmbreeBackendTest, OccludedAndBatchesAgreeWithIntersect) {
  SceneGeometry g;
  g.meshes.push_back(make_grid(0, 10, 0.0f));
  for (std::uint32_t k = 0; k < 20; ++k) {
    const float x = static_cast<float>(k % 5) * 2.0f + 1.0f, y = static_cast<float>(k / 5) * 2.5f + 1.0f;
    g.spheres.push_back(make_sphere(k + 1, {x, y, 1.0f + 0.1f * static_cast<float>(k)}, 0.3f + 0.05f * static_cast<float>(k % 4)));
  }
  auto backend = build(g);
  Rng rng(11, 3);
  std::vector<Ray> rays;
  for (int k = 0; k < 3000; ++k) {
    const glm::vec3 org{rng.next_float() * 12.0f - 1.0f, rng.next_float() * 12.0f - 1.0f, rng.next_float() * 6.0f - 1.0f};
    const glm::vec3 dir{rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f};
    const float tmax = k % 3 == 0 ? rng.next_float() * 4.0f : kInf;
    rays.push_back(make_ray(org, dir, 0.0f, tmax));
  }
  std::vector<Hit> hits(rays.size());
  std::vector<std::uint8_t> occ(rays.size());
  backend->intersect(rays, hits, nullptr);
  backend->occluded(rays, occ, nullptr);
  std::size_t found = 0;
  for (std::size_t k = 0; k < rays.size(); ++k) {
    Hit single;
    const bool hit = backend->intersect(rays[k], single);
    found += hit ? 1 : 0;
    EXPECT_EQ(backend->occluded(rays[k]), hit) << k;
    EXPECT_EQ(occ[k] != 0, hit) << k;
    EXPECT_EQ(hits[k].found(), hit) << k;
    if (hit && hits[k].found()) {
      EXPECT_EQ(hits[k].t, single.t) << k;
      EXPECT_EQ(hits[k].geom_id, single.geom_id) << k;
      EXPECT_EQ(hits[k].prim_id, single.prim_id) << k;
      EXPECT_EQ(hits[k].ng, single.ng) << k;
    }
  }
  // Both outcomes are well represented, so the agreement above means something.
  EXPECT_GT(found, rays.size() / 10);
  EXPECT_LT(found, rays.size() * 9 / 10);
}

INSTANTIATE_TEST_SUITE_P(Embree, EmbreeBackendTest, ::testing::Values(true, false),
                         [](const ::testing::TestParamInfo<bool>& p) { return p.param ? "robust" : "fast"; });

// Rays exactly through the shared edges and vertices of a grid: the robust flag must not lose any.
// Only `embree` promises it (traits().watertight); `embree-fast` is not tested for it.
TEST(EmbreeRobust, LosesNoRayThroughSharedEdgesAndVertices) {
  const ScopedFlushDenormals ftz;
  SceneGeometry g;
  g.meshes.push_back(make_grid(0, 8, 0.0f));
  auto backend = make_embree_backend(/*robust=*/true);
  backend->build(g);
  int lost = 0;
  for (int j = 1; j < 8; ++j)
    for (int i = 1; i < 8; ++i) {
      const glm::vec3 target{static_cast<float>(i), static_cast<float>(j), 0.0f};
      const std::vector<glm::vec3> origins = {target + glm::vec3(0.37f, -0.61f, 2.3f), target + glm::vec3(-1.1f, 0.2f, 0.7f),
                                              target + glm::vec3(0, 0, 1)};
      for (const glm::vec3& o : origins) lost += backend->occluded(make_ray(o, target - o)) ? 0 : 1;
      // Through the diagonal edge's midpoint and a vertical edge's midpoint.
      for (const glm::vec3& t : {target + glm::vec3(0.5f, 0.5f, 0), target + glm::vec3(0, 0.5f, 0)}) {
        const glm::vec3 o = t + glm::vec3(0.3f, 0.45f, 1.7f);
        lost += backend->occluded(make_ray(o, t - o)) ? 0 : 1;
      }
    }
  EXPECT_EQ(lost, 0);
}

// ---------------------------------------------------------------------------------------------------
// Precision of the two sphere formulations (see docs/embree-backend.md): the backend's user geometry
// running core/intersect/sphere_robust.h, and Embree's native RTC_GEOMETRY_TYPE_SPHERE_POINT.

// The entry root of |org + t dir - c| = r evaluated in long double from the exact float inputs.
long double reference_entry_t(const Ray& ray, const Sphere& s) {
  const long double fx = static_cast<long double>(ray.org.x) - s.center.x;
  const long double fy = static_cast<long double>(ray.org.y) - s.center.y;
  const long double fz = static_cast<long double>(ray.org.z) - s.center.z;
  const long double dx = ray.dir.x, dy = ray.dir.y, dz = ray.dir.z;
  const long double a = dx * dx + dy * dy + dz * dz;
  const long double b = fx * dx + fy * dy + fz * dz;
  const long double r = s.radius;
  const long double c = fx * fx + fy * fy + fz * fz - r * r;
  const long double disc = b * b - a * c;
  if (disc < 0) return std::numeric_limits<long double>::quiet_NaN();
  // Entry root -(b + sqrt(disc)) / a, written without cancellation (b < 0 when the sphere is ahead).
  return c / (-b + std::sqrt(disc));
}

struct SpherePrecisionCase {
  const char* label;
  Sphere sphere;
  Ray ray;
};

std::vector<SpherePrecisionCase> sphere_precision_cases() {
  std::vector<SpherePrecisionCase> cases;
  // Huge sphere, origin ~3 units from its surface, oblique ray.
  const Sphere huge = make_sphere(0, {1000.5f, -2000.25f, -100003.0f}, 1.0e5f);
  cases.push_back({"huge r=1e5, 3 units away", huge,
                   make_ray({1000.5f + 0.1f, -2000.25f + 0.2f, 0.3f}, glm::normalize(glm::vec3(0.05f, -0.03f, -1.0f)))});
  // Tiny sphere 1e4 units away, ray aimed off-centre by 0.4 radius.
  const Sphere tiny = make_sphere(0, {5000.125f, -3000.5f, -7500.25f}, 1.0e-3f);
  const glm::vec3 org{0.5f, 0.25f, -0.125f};
  cases.push_back({"tiny r=1e-3, 1e4 away", tiny, make_ray(org, (tiny.center + glm::vec3(4e-4f, 0, 0)) - org)});
  return cases;
}

double relative_error(float t, long double ref) {
  return static_cast<double>(std::fabs((static_cast<long double>(t) - ref) / ref));
}

// The backend's spheres are as accurate as float t can be: within one float ulp of the exact root.
TEST(EmbreeSpherePrecision, UserGeometryIsWithinOneUlpOfTheLongDoubleRoot) {
  const ScopedFlushDenormals ftz;
  for (const SpherePrecisionCase& c : sphere_precision_cases()) {
    for (const bool robust : {true, false}) {
      SceneGeometry g;
      g.spheres.push_back(c.sphere);
      auto backend = make_embree_backend(robust);
      backend->build(g);
      const long double ref = reference_entry_t(c.ray, c.sphere);
      ASSERT_FALSE(std::isnan(ref)) << c.label;
      Hit hit;
      ASSERT_TRUE(backend->intersect(c.ray, hit)) << c.label;
      const double err = relative_error(hit.t, ref);
      std::printf("[ sphere precision ] %-26s user geometry (%s): relative t error %.3g\n", c.label,
                  robust ? "robust" : "fast", err);
      EXPECT_LE(err, 0x1p-23) << c.label;  // one ulp of a float in [1, 2)
    }
  }
}

// Embree's native float formulation, measured for the record (docs/embree-backend.md); not asserted
// beyond "it is a number or a miss", since its accuracy is Embree's business, not a contract of ours.
TEST(EmbreeSpherePrecision, MeasureNativeSpherePoint) {
  const ScopedFlushDenormals ftz;
  RTCDevice device = rtcNewDevice(nullptr);
  ASSERT_NE(device, nullptr);
  for (const SpherePrecisionCase& c : sphere_precision_cases()) {
    RTCScene scene = rtcNewScene(device);
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    auto* v = static_cast<float*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
    v[0] = c.sphere.center.x;
    v[1] = c.sphere.center.y;
    v[2] = c.sphere.center.z;
    v[3] = c.sphere.radius;
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene);
    ASSERT_EQ(rtcGetDeviceError(device), RTC_ERROR_NONE);

    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh{};
    rh.ray.org_x = c.ray.org.x;
    rh.ray.org_y = c.ray.org.y;
    rh.ray.org_z = c.ray.org.z;
    rh.ray.dir_x = c.ray.dir.x;
    rh.ray.dir_y = c.ray.dir.y;
    rh.ray.dir_z = c.ray.dir.z;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = kInf;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &context, &rh);
    const long double ref = reference_entry_t(c.ray, c.sphere);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
      std::printf("[ sphere precision ] %-26s SPHERE_POINT: MISS (exact entry t = %.9Lg)\n", c.label, ref);
    } else {
      const double err = relative_error(rh.ray.tfar, ref);
      std::printf("[ sphere precision ] %-26s SPHERE_POINT: relative t error %.3g\n", c.label, err);
      RecordProperty(std::string("sphere_point_rel_error ") + c.label, std::to_string(err));
      EXPECT_FALSE(std::isnan(err));
    }
    rtcReleaseScene(scene);
  }
  rtcReleaseDevice(device);
}

}  // namespace
}  // namespace twinray
