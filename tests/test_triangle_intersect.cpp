// Watertight ray-triangle test (core/intersect/triangle_watertight.h): exact hits, edge and vertex
// ownership on a grid mesh, signed-zero and axis-aligned directions, parallel and in-plane rays,
// degenerate triangles.

#include "core/intersect/triangle_watertight.h"
#include "core/scene/procedural.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace twinray {
namespace {

struct TriangleHitResult {
  bool hit = false;
  float t = 0.0f, u = 0.0f, v = 0.0f;
};

TriangleHitResult trace(const glm::vec3& org, const glm::vec3& dir, const glm::vec3& p0, const glm::vec3& p1,
                        const glm::vec3& p2, float tmin = 0.0f,
                        float tmax = std::numeric_limits<float>::infinity()) {
  TriangleHitResult r;
  r.hit = intersect_triangle(make_triangle_ray(org, dir), p0, p1, p2, tmin, tmax, r.t, r.u, r.v);
  return r;
}

// How many triangles of the mesh the ray hits, testing every one (no early exit, no closest-hit logic).
int count_hits(const TriangleMesh& mesh, const glm::vec3& org, const glm::vec3& dir) {
  const TriangleRay ray = make_triangle_ray(org, dir);
  int hits = 0;
  for (const glm::uvec3& tri : mesh.indices) {
    float t, u, v;
    hits += intersect_triangle(ray, mesh.positions[tri.x], mesh.positions[tri.y], mesh.positions[tri.z], 0.0f,
                               std::numeric_limits<float>::infinity(), t, u, v)
                ? 1
                : 0;
  }
  return hits;
}

const glm::vec3 kP0{0.0f, 0.0f, 0.0f}, kP1{1.0f, 0.0f, 0.0f}, kP2{0.0f, 1.0f, 0.0f};

TEST(TriangleIntersect, ExactHitFromBothSides) {
  // Dyadic numbers: every intermediate is exact, so t, u, v are exact.
  const TriangleHitResult front = trace({0.25f, 0.5f, 2.0f}, {0.0f, 0.0f, -1.0f}, kP0, kP1, kP2);
  ASSERT_TRUE(front.hit);
  EXPECT_EQ(front.t, 2.0f);
  EXPECT_EQ(front.u, 0.25f);  // weight of p1 = x
  EXPECT_EQ(front.v, 0.5f);   // weight of p2 = y
  // No backface culling, same barycentrics from behind.
  const TriangleHitResult back = trace({0.25f, 0.5f, -4.0f}, {0.0f, 0.0f, 2.0f}, kP0, kP1, kP2);
  ASSERT_TRUE(back.hit);
  EXPECT_EQ(back.t, 2.0f);
  EXPECT_EQ(back.u, 0.25f);
  EXPECT_EQ(back.v, 0.5f);
}

TEST(TriangleIntersect, IntervalIsClosed) {
  const glm::vec3 org{0.25f, 0.25f, 1.0f}, dir{0.0f, 0.0f, -1.0f};
  EXPECT_TRUE(trace(org, dir, kP0, kP1, kP2, 0.0f, 1.0f).hit);
  EXPECT_TRUE(trace(org, dir, kP0, kP1, kP2, 1.0f, 1.0f).hit);
  EXPECT_FALSE(trace(org, dir, kP0, kP1, kP2, 0.0f, std::nextafter(1.0f, 0.0f)).hit);
  EXPECT_FALSE(trace(org, dir, kP0, kP1, kP2, std::nextafter(1.0f, 2.0f), 5.0f).hit);
  // Behind the origin.
  EXPECT_FALSE(trace(org, -dir, kP0, kP1, kP2).hit);
}

TEST(TriangleIntersect, AxisAlignedDirectionsWithSignedZeros) {
  // A triangle perpendicular to each axis, hit along +axis and -axis, with every combination of +0 / -0
  // in the other two components.
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    glm::vec3 p0(0.0f), p1(0.0f), p2(0.0f);
    p1[a1] = 1.0f;
    p2[a2] = 1.0f;
    for (float sign : {1.0f, -1.0f}) {
      for (int zeros = 0; zeros < 4; ++zeros) {
        glm::vec3 dir;
        dir[axis] = sign;
        dir[a1] = (zeros & 1) ? -0.0f : 0.0f;
        dir[a2] = (zeros & 2) ? -0.0f : 0.0f;
        glm::vec3 org(0.0f);
        org[a1] = 0.125f;
        org[a2] = 0.375f;
        org[axis] = -3.0f * sign;
        const TriangleHitResult r = trace(org, dir, p0, p1, p2);
        ASSERT_TRUE(r.hit) << "axis " << axis << " sign " << sign << " zeros " << zeros;
        EXPECT_EQ(r.t, 3.0f);
        EXPECT_EQ(r.u, 0.125f);
        EXPECT_EQ(r.v, 0.375f);
      }
    }
  }
}

TEST(TriangleIntersect, RayThroughSharedVerticesAndEdgesHitsExactlyOneTriangle) {
  const SceneGeometry grid = grid_mesh(6, 6);
  const TriangleMesh& mesh = grid.meshes[0];
  // Directions with integer components, so the ray org = target - 0.5 dir passes exactly through the target.
  const std::vector<glm::vec3> dirs = {
      {0.0f, 0.0f, -1.0f}, {0.0f, 0.0f, 1.0f},  {-0.0f, 0.0f, -1.0f}, {0.0f, -0.0f, 1.0f}, {-0.0f, -0.0f, -1.0f},
      {1.0f, 2.0f, -4.0f}, {-3.0f, 1.0f, 2.0f}, {2.0f, -2.0f, -1.0f}, {1.0f, 1.0f, -1.0f}, {-1.0f, 0.0f, -1.0f},
      {0.0f, 5.0f, 1.0f},  {7.0f, -3.0f, -2.0f}, {-1.0f, -1.0f, 8.0f}, {1.0f, -1.0f, 1.0f}};
  int rays = 0;
  // Interior targets only: the grid's boundary is not surrounded by triangles.
  for (int j = 1; j < 6; ++j) {
    for (int i = 1; i < 6; ++i) {
      const float x = static_cast<float>(i), y = static_cast<float>(j);
      const std::vector<glm::vec3> targets = {
          {x, y, 0.0f},            // vertex (valence 4 or 8)
          {x + 0.5f, y, 0.0f},     // horizontal edge
          {x, y + 0.5f, 0.0f},     // vertical edge
          {x + 0.5f, y + 0.5f, 0.0f},  // diagonal edge (both diagonal directions occur)
          {x - 0.25f, y + 0.25f, 0.0f}};  // on a diagonal in every other square
      for (const glm::vec3& target : targets) {
        for (const glm::vec3& dir : dirs) {
          const glm::vec3 org = target - 0.5f * dir;
          EXPECT_EQ(count_hits(mesh, org, dir), 1) << "target (" << target.x << ", " << target.y << ") dir (" << dir.x
                                                   << ", " << dir.y << ", " << dir.z << ")";
          ++rays;
        }
      }
    }
  }
  EXPECT_EQ(rays, 5 * 5 * 5 * 14);
}

TEST(TriangleIntersect, ParallelAndInPlaneRaysMissWithoutNaN) {
  // Parallel to the plane, above it.
  EXPECT_FALSE(trace({-1.0f, 0.25f, 0.5f}, {1.0f, 0.0f, 0.0f}, kP0, kP1, kP2).hit);
  EXPECT_FALSE(trace({-1.0f, 0.25f, 0.5f}, {1.0f, -0.0f, -0.0f}, kP0, kP1, kP2).hit);
  // In the plane, crossing the triangle: determinant 0, no single crossing point, documented as a miss.
  EXPECT_FALSE(trace({-1.0f, 0.25f, 0.0f}, {1.0f, 0.0f, 0.0f}, kP0, kP1, kP2).hit);
  EXPECT_FALSE(trace({-1.0f, -1.0f, 0.0f}, {1.0f, 1.0f, 0.0f}, kP0, kP1, kP2).hit);
  // Along an edge line.
  EXPECT_FALSE(trace({-1.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}, kP0, kP1, kP2).hit);
  const SceneGeometry grid = grid_mesh(4, 4);
  EXPECT_EQ(count_hits(grid.meshes[0], {-1.0f, 2.0f, 0.0f}, {1.0f, 0.0f, 0.0f}), 0);
  EXPECT_EQ(count_hits(grid.meshes[0], {-1.0f, -0.5f, 0.0f}, {1.0f, 1.0f, 0.0f}), 0);
}

TEST(TriangleIntersect, DegenerateTrianglesMissAndNearDegenerateOnesStayFinite) {
  // Collinear vertices and a repeated vertex.
  EXPECT_FALSE(trace({1.0f, 1.0f, 1.0f}, {0.0f, 0.0f, -1.0f}, {0, 0, 0}, {1, 1, 0}, {2, 2, 0}).hit);
  EXPECT_FALSE(trace({0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, -1.0f}, {0, 0, 0}, {0, 0, 0}, {1, 0, 0}).hit);
  // A sliver 1e-7 high, hit in its middle.
  const glm::vec3 q0{0.0f, 0.0f, 0.0f}, q1{1.0f, 0.0f, 0.0f}, q2{0.5f, 1e-7f, 0.0f};
  const TriangleHitResult r = trace({0.5f, 2e-8f, 1.0f}, {0.0f, 0.0f, -1.0f}, q0, q1, q2);
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.t, 1.0f);
  EXPECT_TRUE(std::isfinite(r.u) && std::isfinite(r.v));
  EXPECT_NEAR(r.v, 0.2f, 1e-5f);
  const glm::vec3 n = triangle_geometric_normal(q0, q1, q2);
  EXPECT_FLOAT_EQ(n.z, 1.0f);
  // A tiny triangle whose float cross product would underflow still gets a unit normal.
  const glm::vec3 t0{1.0f, 1.0f, 1.0f}, t1 = t0 + glm::vec3(1e-20f, 0.0f, 0.0f), t2 = t0 + glm::vec3(0.0f, 1e-20f, 0.0f);
  EXPECT_FLOAT_EQ(glm::length(triangle_geometric_normal(t0, t1, t2)), 1.0f);
}

TEST(TriangleIntersect, GeometricNormalFollowsCounterClockwiseWinding) {
  EXPECT_EQ(triangle_geometric_normal(kP0, kP1, kP2), glm::vec3(0.0f, 0.0f, 1.0f));
  EXPECT_EQ(triangle_geometric_normal(kP0, kP2, kP1), glm::vec3(0.0f, 0.0f, -1.0f));
}

}  // namespace
}  // namespace twinray
