// Watertightness: rays from inside closed tessellated spheres must always hit, and must cross the surface
// exactly once (an any-order loop over every triangle counts one hit), near the origin and far from it,
// where float spacing is coarse (ulp(2^17) = 2^-6). Both bvh and brute are checked.

#include "backends/brute/brute_backend.h"
#include "backends/bvh/bvh_backend.h"
#include "core/intersect/triangle_watertight.h"
#include "core/sampling/rng.h"
#include "core/scene/procedural.h"
#include "ray_test_util.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <limits>
#include <map>
#include <utility>
#include <vector>

namespace twinray {
namespace {

using test::kInf;

// Rays from random points well inside the sphere (within a quarter radius of the center) in random
// directions; one in four aims exactly at a mesh vertex and one in four has zero components (+0 / -0).
std::vector<Ray> inside_rays(const TriangleMesh& mesh, const glm::vec3& center, float radius, int n, std::uint64_t seed) {
  Rng rng(seed, 0);
  std::vector<Ray> rays(static_cast<std::size_t>(n));
  const auto symmetric = [&rng] { return 2.0f * rng.next_float() - 1.0f; };
  for (Ray& r : rays) {
    r.org = center + 0.25f * radius * glm::vec3(symmetric(), symmetric(), symmetric());
    switch (rng.next_below(4)) {
      case 0: r.dir = mesh.positions[rng.next_below(static_cast<std::uint32_t>(mesh.positions.size()))] - r.org; break;
      case 1:
        r.dir = glm::vec3(symmetric(), rng.next_below(2) ? 0.0f : -0.0f, symmetric());
        if (rng.next_below(2)) r.dir.z = rng.next_below(2) ? 0.0f : -0.0f;
        break;
      default: r.dir = glm::vec3(symmetric(), symmetric(), symmetric()); break;
    }
    if (r.dir.x == 0.0f && r.dir.y == 0.0f && r.dir.z == 0.0f) r.dir.x = 1.0f;
  }
  return rays;
}

int count_crossings(const TriangleMesh& mesh, const Ray& ray) {
  const TriangleRay tri_ray = make_triangle_ray(ray.org, ray.dir);
  int count = 0;
  for (const glm::uvec3& tri : mesh.indices) {
    float t, u, v;
    count += intersect_triangle(tri_ray, mesh.positions[tri.x], mesh.positions[tri.y], mesh.positions[tri.z], 0.0f,
                                kInf, t, u, v)
                 ? 1
                 : 0;
  }
  return count;
}

void expect_watertight(const glm::vec3& center, float radius) {
  const SceneGeometry sphere = tessellated_sphere(center, radius, 4);  // 5120 triangles
  const TriangleMesh& mesh = sphere.meshes[0];
  const std::unique_ptr<Backend> bvh = make_bvh_backend();
  const std::unique_ptr<Backend> brute = make_brute_backend();
  bvh->build(sphere);
  brute->build(sphere);

  std::size_t bvh_misses = 0, bvh_not_occluded = 0;
  for (const Ray& ray : inside_rays(mesh, center, radius, 100000, 1)) {
    Hit hit;
    bvh_misses += bvh->intersect(ray, hit) ? 0 : 1;
    bvh_not_occluded += bvh->occluded(ray) ? 0 : 1;
  }
  EXPECT_EQ(bvh_misses, 0u);
  EXPECT_EQ(bvh_not_occluded, 0u);

  // The oracle and the exact crossing count cost a full sweep per ray: fewer rays.
  std::size_t brute_misses = 0, not_exactly_once = 0;
  for (const Ray& ray : inside_rays(mesh, center, radius, 1500, 2)) {
    Hit hit;
    brute_misses += brute->intersect(ray, hit) ? 0 : 1;
    not_exactly_once += count_crossings(mesh, ray) == 1 ? 0 : 1;
  }
  EXPECT_EQ(brute_misses, 0u);
  EXPECT_EQ(not_exactly_once, 0u);
}

TEST(Watertight, ClosedSphereNearTheOrigin) { expect_watertight(glm::vec3(0.0f), 1.0f); }

TEST(Watertight, ClosedSphereFarFromTheOrigin) { expect_watertight({148376.0f, 1234.0f, -223423.0f}, 1000.0f); }

TEST(Watertight, TessellatedSphereIsClosedAndOutwardFacing) {
  const SceneGeometry sphere = tessellated_sphere(glm::vec3(0.0f), 1.0f, 3);
  const TriangleMesh& mesh = sphere.meshes[0];
  EXPECT_EQ(mesh.indices.size(), 20u * 64u);
  EXPECT_EQ(mesh.positions.size(), 10u * 64u + 2u);  // Euler: V = E - F + 2 with E = 3F/2
  EXPECT_GT(mesh.positions.capacity(), mesh.positions.size());
  // Every directed edge appears once and its reverse once: closed and consistently oriented.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const glm::uvec3& tri : mesh.indices) {
    for (int k = 0; k < 3; ++k) ++directed[{tri[k], tri[(k + 1) % 3]}];
    const glm::vec3 n = triangle_geometric_normal(mesh.positions[tri.x], mesh.positions[tri.y], mesh.positions[tri.z]);
    EXPECT_GT(glm::dot(n, mesh.positions[tri.x]), 0.0f);  // outward
  }
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u);
  }
}

}  // namespace
}  // namespace twinray
