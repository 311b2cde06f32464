// Backend::intersect_ids (t and ids only) and the surface point the renderer builds from them
// (core/render/triangle_surface.h, make_surface_point): every backend gives the t and ids of intersect(),
// and the point and normal agree with those made from a full closest hit's certified u, v and ng.

#include "backends/registry.h"
#include "backends/simd/isa.h"
#include "backends/wide/wide_backend.h"
#include "core/intersect/sphere_robust.h"
#include "core/render/light_transport.h"
#include "core/scene/mesh_scene.h"
#include "core/scene/procedural.h"
#include "core/util/fp_mode.h"
#include "harness/crosscheck/ray_generation.h"
#include "ray_test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace twinray {
namespace {

using test::same_bits;

Scene mixed_scene() {
  Scene s;
  s.geometry = mixed_spheres_and_triangles(30, 600, 5);
  s.camera = framing_camera(s.geometry.bounds(), 64, 48, 40.0f);
  Material grey;
  grey.name = "grey";
  grey.albedo = glm::vec3(0.5f);
  s.materials = {grey};
  s.shapes.resize(s.geometry.geom_id_end());
  for (const Sphere& sp : s.geometry.spheres) s.shapes[sp.geom_id].kind = ShapeKind::Sphere;
  return s;
}

std::vector<Ray> rays_of_every_kind(const Scene& scene, const Backend& hit_source) {
  std::vector<Ray> rays;
  for (const crosscheck::RayKind kind : crosscheck::kAllRayKinds) {
    const std::vector<Ray> some = crosscheck::generate_rays(kind, scene, hit_source, 800, 17);
    rays.insert(rays.end(), some.begin(), some.end());
  }
  return rays;
}

struct NamedBackend {
  std::string name;
  std::unique_ptr<Backend> backend;
};

std::vector<NamedBackend> every_backend() {
  std::vector<NamedBackend> v;
  for (const Isa isa : runnable_isas())
    v.push_back({"bvh8 " + std::string(to_string(isa)), make_wide_backend({}, isa)});
  for (const char* name : {"bvh", "brute", "embree"}) v.push_back({name, make_backend(name)});
  return v;
}

TEST(IntersectIds, SameTAndIdsAsIntersectOnEveryBackend) {
  const ScopedFlushDenormals ftz;
  const Scene scene = mixed_scene();
  std::vector<NamedBackend> backends = every_backend();
  for (NamedBackend& b : backends) b.backend->build(scene.geometry);
  const std::vector<Ray> rays = rays_of_every_kind(scene, *backends.front().backend);
  ASSERT_GT(rays.size(), 3000u);
  for (const NamedBackend& b : backends) {
    SCOPED_TRACE(b.name);
    std::size_t hits = 0, sphere_hits = 0;
    for (const Ray& r : rays) {
      Hit full, ids;
      const bool found = b.backend->intersect(r, full);
      ASSERT_EQ(b.backend->intersect_ids(r, ids), found);
      ASSERT_EQ(ids.found(), found);
      if (!found) continue;
      ++hits;
      sphere_hits += scene.shapes[full.geom_id].kind == ShapeKind::Sphere ? 1 : 0;
      ASSERT_TRUE(same_bits(ids.t, full.t));
      ASSERT_EQ(ids.geom_id, full.geom_id);
      ASSERT_EQ(ids.prim_id, full.prim_id);
    }
    EXPECT_GT(hits, 1000u);
    EXPECT_GT(sphere_hits, 50u);
    // An invalid ray is a miss, as for intersect().
    Hit h;
    EXPECT_FALSE(b.backend->intersect_ids(test::make_ray({0, 0, 0}, {0, 0, 0}), h));
    EXPECT_FALSE(h.found());
  }
}

// The renderer's surface point from t and the ids against the point from the certified barycentrics (bvh8's
// full answer): the same normal bit for bit, a point in the triangle's plane up to ulps of the vertices, and
// within the rounding of org + t dir of the certified point; spheres exactly as sphere_hit_point.
TEST(IntersectIds, SurfacePointAgreesWithTheCertifiedHit) {
  const ScopedFlushDenormals ftz;
  const Scene scene = mixed_scene();
  const std::unique_ptr<Backend> backend = make_backend("bvh8");
  backend->build(scene.geometry);
  const SceneContext ctx = SceneContext::make(scene, *backend, nullptr, nullptr);
  std::size_t triangles = 0, spheres = 0;
  for (const Ray& r : rays_of_every_kind(scene, *backend)) {
    Hit hit;
    if (!backend->intersect(r, hit)) continue;
    Hit ids;
    backend->intersect_ids(r, ids);
    const SurfacePoint sp = make_surface_point(ctx, r, ids);
    ASSERT_EQ(sp.geom, &ctx.geoms[hit.geom_id]);
    ASSERT_TRUE(same_bits(sp.ng.x, hit.ng.x) && same_bits(sp.ng.y, hit.ng.y) && same_bits(sp.ng.z, hit.ng.z));
    if (sp.geom->sphere) {
      const Sphere& s = scene.geometry.spheres[sp.geom->shape];
      const glm::vec3 p = sphere_hit_point(r.org, r.dir, hit.t, s.center, s.radius);
      ASSERT_TRUE(same_bits(sp.p.x, p.x) && same_bits(sp.p.y, p.y) && same_bits(sp.p.z, p.z));
      ++spheres;
      continue;
    }
    const TriangleMesh& m = scene.geometry.meshes[sp.geom->shape];
    const glm::uvec3 tri = m.indices[hit.prim_id];
    const glm::dvec3 p0(m.positions[tri.x]), p1(m.positions[tri.y]), p2(m.positions[tri.z]);
    const glm::dvec3 certified = (1.0 - hit.u - hit.v) * p0 + static_cast<double>(hit.u) * p1 + static_cast<double>(hit.v) * p2;
    const glm::dvec3 p(sp.p);
    const double scale = static_cast<double>(sp.error_scale);
    // In the plane: 4 ulps of the vertex magnitude (the rebuild p0 + u e1 + v e2 and the normal round a few
    // times; 0.87 ulps at most seen here).
    EXPECT_LE(std::abs(glm::dot(p - p0, glm::dvec3(hit.ng))), 8.0 * 0x1p-24 * scale);
    // Near the certified point: the rounding of org + t dir, ulps of |org| + t |dir|, plus the above (at most
    // 0.52 ulps of their sum seen here).
    const double reach = glm::length(glm::dvec3(r.org)) + static_cast<double>(hit.t) * glm::length(glm::dvec3(r.dir));
    EXPECT_LE(glm::length(p - certified), 4.0 * 0x1p-24 * (reach + scale));
    ++triangles;
  }
  EXPECT_GT(triangles, 1000u);
  EXPECT_GT(spheres, 50u);
}

TEST(TriangleSurface, PointStaysOnTheTriangle) {
  const TriangleSurface s = TriangleSurface::make({1, 0, 0}, {3, 0, 0}, {1, 2, 0});
  EXPECT_EQ(s.error_scale, 3.0f);
  EXPECT_EQ(s.ng, glm::vec3(0, 0, 1));
  // Inside: the crossing itself, whatever the ray.
  const Ray down = test::make_ray({1.5f, 0.5f, 4}, {0, 0, -1});
  EXPECT_EQ(s.point(down, 4.0f), glm::vec3(1.5f, 0.5f, 0));
  // A t that overshoots (a point off the plane) is projected back onto it.
  const glm::vec3 off = s.point(test::make_ray({1.5f, 0.5f, 4}, {0, 0, -1}), 4.5f);
  EXPECT_EQ(off, glm::vec3(1.5f, 0.5f, 0));
  // Beyond an edge or a vertex: clamped onto the triangle.
  EXPECT_EQ(s.point(test::make_ray({5, -1, 1}, {0, 0, -1}), 1.0f), glm::vec3(3, 0, 0));
  EXPECT_EQ(s.point(test::make_ray({2, -1, 1}, {0, 0, -1}), 1.0f), glm::vec3(2, 0, 0));
  // Collinear vertices (never hit): the point is p0, never NaN.
  const TriangleSurface flat = TriangleSurface::make({0, 0, 0}, {1, 1, 1}, {2, 2, 2});
  EXPECT_EQ(flat.point(down, 4.0f), glm::vec3(0, 0, 0));
}

}  // namespace
}  // namespace twinray
