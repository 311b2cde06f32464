// Geometry cleanup: exactly degenerate and non-finite triangles go, everything with area stays.

#include "core/scene/geometry_cleanup.h"

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>

namespace twinray {
namespace {

TEST(GeometryCleanup, DropsEachKindOfDegenerateTriangleAndCountsIt) {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {1, 0, 0}};
  mesh.indices = {
      {0, 1, 2},  // fine
      {0, 0, 2},  // repeated index
      {0, 1, 4},  // vertices 1 and 4 share a position
      {0, 1, 3},  // collinear: zero area
      {2, 1, 0},  // fine (other winding)
  };
  LoadReport report;
  remove_invalid_triangles(mesh, report);
  EXPECT_EQ(report.degenerate_triangles, 3u);
  EXPECT_EQ(report.nonfinite_triangles, 0u);
  ASSERT_EQ(mesh.indices.size(), 2u);
  EXPECT_EQ(mesh.indices[0], glm::uvec3(0, 1, 2));
  EXPECT_EQ(mesh.indices[1], glm::uvec3(2, 1, 0));
}

TEST(GeometryCleanup, KeepsTrianglesWhoseFloatCrossProductCancelsToZero) {
  // n.x = a*d - b*c with a = d = 1 + 2^-23, b = 1, c = 1 + 2^-22: exactly 2^-46, but both products round to
  // 1 + 2^-22 in float, so a float area test would call this (valid, if thin) triangle degenerate.
  const float a = 1.0f + 0x1p-23f, b = 1.0f, c = 1.0f + 0x1p-22f, d = a;
  volatile float ad = a * d, bc = b * c;  // volatile: force float rounding of each product
  ASSERT_EQ(ad - bc, 0.0f) << "premise: the float cross product cancels";

  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {0, a, b}, {0, c, d}};
  mesh.indices = {{0, 1, 2}};
  LoadReport report;
  remove_invalid_triangles(mesh, report);
  EXPECT_EQ(report.degenerate_triangles, 0u);
  EXPECT_EQ(mesh.indices.size(), 1u);
}

TEST(GeometryCleanup, DropsTrianglesWithNonFiniteVerticesAndCountsThemSeparately) {
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {nan, 0, 0}, {0, inf, 0}};
  mesh.indices = {{0, 1, 3}, {0, 1, 2}, {4, 1, 2}, {3, 3, 3}};
  LoadReport report;
  remove_invalid_triangles(mesh, report);
  EXPECT_EQ(report.nonfinite_triangles, 3u);
  EXPECT_EQ(report.degenerate_triangles, 0u);
  ASSERT_EQ(mesh.indices.size(), 1u);
  EXPECT_EQ(mesh.indices[0], glm::uvec3(0, 1, 2));
}

TEST(GeometryCleanup, OutOfRangeIndexIsAProgrammingError) {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.indices = {{0, 1, 3}};
  LoadReport report;
  EXPECT_THROW(remove_invalid_triangles(mesh, report), std::invalid_argument);
}

TEST(GeometryCleanup, CleanGeometryPadsVertexBuffersAndDropsEmptyMeshes) {
  SceneGeometry geometry;
  TriangleMesh good;
  good.geom_id = 0;
  good.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  good.positions.shrink_to_fit();
  good.indices = {{0, 1, 2}};
  TriangleMesh all_degenerate;
  all_degenerate.geom_id = 1;
  all_degenerate.positions = {{0, 0, 0}, {1, 0, 0}};
  all_degenerate.indices = {{0, 1, 1}};
  geometry.meshes = {good, all_degenerate};
  Sphere sphere;
  sphere.geom_id = 2;
  geometry.spheres = {sphere};

  LoadReport report;
  clean_geometry(geometry, report);
  ASSERT_EQ(geometry.meshes.size(), 1u);
  EXPECT_EQ(geometry.meshes[0].geom_id, 0u);
  EXPECT_GT(geometry.meshes[0].positions.capacity(), geometry.meshes[0].positions.size());
  EXPECT_EQ(geometry.spheres.size(), 1u);
  EXPECT_EQ(report.degenerate_triangles, 1u);
}

}  // namespace
}  // namespace twinray
