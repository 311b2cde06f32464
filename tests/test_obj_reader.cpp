// OBJ reader: the statements real exporters write, parsed exactly.

#include "core/scene/obj_reader.h"
#include "core/util/input_error.h"

#include <gtest/gtest.h>

#include <string>

namespace twinray {
namespace {

TriangleMesh parse(const std::string& text, LoadReport& report) { return parse_obj(text, "test.obj", report); }

TEST(ObjReader, ReadsTrianglesWithExactCoordinates) {
  LoadReport report;
  const TriangleMesh mesh = parse("v 0 0 0\nv 1.5 -2.25 1e2\nv .5 +3 -1E-1\nf 1 2 3\n", report);
  ASSERT_EQ(mesh.positions.size(), 3u);
  EXPECT_EQ(mesh.positions[1], glm::vec3(1.5f, -2.25f, 100.0f));
  // Correctly rounded: the float nearest to -0.1, as a compiler would produce for -0.1f.
  EXPECT_EQ(mesh.positions[2], glm::vec3(0.5f, 3.0f, -0.1f));
  ASSERT_EQ(mesh.indices.size(), 1u);
  EXPECT_EQ(mesh.indices[0], glm::uvec3(0, 1, 2));
  EXPECT_EQ(report.polygons_triangulated, 0u);
}

TEST(ObjReader, SplitsPolygonsIntoFansAndCountsThem) {
  LoadReport report;
  const TriangleMesh mesh =
      parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 1 0\nf 1 2 3 4\nf 1 2 3 4 5\nf 1 2 3\n", report);
  ASSERT_EQ(mesh.indices.size(), 2u + 3u + 1u);
  EXPECT_EQ(mesh.indices[0], glm::uvec3(0, 1, 2));
  EXPECT_EQ(mesh.indices[1], glm::uvec3(0, 2, 3));
  EXPECT_EQ(mesh.indices[2], glm::uvec3(0, 1, 2));
  EXPECT_EQ(mesh.indices[3], glm::uvec3(0, 2, 3));
  EXPECT_EQ(mesh.indices[4], glm::uvec3(0, 3, 4));
  EXPECT_EQ(report.polygons_triangulated, 2u);
}

TEST(ObjReader, ResolvesNegativeIndicesAgainstVerticesSoFar) {
  LoadReport report;
  const TriangleMesh mesh =
      parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf -4 -1 -2\nf 1 -3 4\n", report);
  ASSERT_EQ(mesh.indices.size(), 3u);
  EXPECT_EQ(mesh.indices[0], glm::uvec3(0, 1, 2));
  EXPECT_EQ(mesh.indices[1], glm::uvec3(0, 3, 2));
  EXPECT_EQ(mesh.indices[2], glm::uvec3(0, 1, 3));
}

TEST(ObjReader, AllCornerFormsGiveTheSamePositions) {
  const std::string vertices = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n";
  for (const char* face : {"f 1 2 3", "f 1/1 2/2 3/3", "f 1//1 2//1 3//1", "f 1/1/1 2/2/1 3/3/1", "f -3/-3/-1 -2/-2/-1 -1/-1/-1"}) {
    LoadReport report;
    const TriangleMesh mesh = parse(vertices + face + "\n", report);
    ASSERT_EQ(mesh.indices.size(), 1u) << face;
    EXPECT_EQ(mesh.indices[0], glm::uvec3(0, 1, 2)) << face;
  }
}

TEST(ObjReader, JoinsStatementsContinuedWithABackslash) {
  LoadReport report;
  // A face and a vertex wrapped over lines (CRLF and blanks after the backslash too); a comment ending in
  // a backslash (a Windows path) does not swallow the face after it.
  const TriangleMesh mesh = parse("v 0 0 0\nv 1 0 \\\n 0\nv 1 1 0\r\nv 0 1 0\n# C:\\models\\\n"
                                  "f 1 2 \\ \r\n  3 \\\n 4\nf 1 \\\n\\\n 2 3\n", report);
  ASSERT_EQ(mesh.positions.size(), 4u);
  EXPECT_EQ(mesh.positions[1], glm::vec3(1.0f, 0.0f, 0.0f));
  ASSERT_EQ(mesh.indices.size(), 3u);
  EXPECT_EQ(mesh.indices[0], glm::uvec3(0, 1, 2));
  EXPECT_EQ(mesh.indices[1], glm::uvec3(0, 2, 3));
  EXPECT_EQ(mesh.indices[2], glm::uvec3(0, 1, 2));
}

TEST(ObjReader, ErrorInAContinuedStatementNamesItsFirstLine) {
  LoadReport report;
  try {
    parse("v 0 0 0\nf 1 \\\n 2 \\\n 9\n", report);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "line 2") << e.what();
  }
}

TEST(ObjReader, MergesObjectsAndIgnoresNonGeometryStatements) {
  LoadReport report;
  const std::string text =
      "# exported\r\nmtllib scene.mtl\r\no first\r\nv 0 0 0\r\nv 1 0 0 1.0\r\nv 0 1 0 0.5 0.5 0.5\r\n"
      "usemtl red\r\ns off\r\nf 1 2 3\r\n\r\ng second group\r\no second\r\n\tv\t2 0 0\r\nv 3 0 0\r\nv 2 1 0\r\n"
      "l 1 2\r\np 3\r\nf -3 -2 -1\r\n";
  const TriangleMesh mesh = parse(text, report);
  ASSERT_EQ(mesh.positions.size(), 6u);
  EXPECT_EQ(mesh.positions[3], glm::vec3(2.0f, 0.0f, 0.0f));
  ASSERT_EQ(mesh.indices.size(), 2u);
  EXPECT_EQ(mesh.indices[1], glm::uvec3(3, 4, 5));
}

TEST(ObjReader, AcceptsForwardReferencesWithinTheFile) {
  LoadReport report;
  const TriangleMesh mesh = parse("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", report);
  ASSERT_EQ(mesh.indices.size(), 1u);
  EXPECT_EQ(mesh.indices[0], glm::uvec3(0, 1, 2));
}

TEST(ObjReader, TinyCoordinatesUnderflowToZeroInsteadOfFailing) {
  LoadReport report;
  const TriangleMesh mesh = parse("v 1e-50 -1e-60 1e-40\n", report);
  ASSERT_EQ(mesh.positions.size(), 1u);
  EXPECT_EQ(mesh.positions[0].x, 0.0f);
  EXPECT_EQ(mesh.positions[0].y, 0.0f);
  EXPECT_EQ(mesh.positions[0].z, 1e-40f);  // subnormal, still representable
}

TEST(ObjReader, FacesWithFewerThanThreeCornersCountAsDegenerate) {
  LoadReport report;
  const TriangleMesh mesh = parse("v 0 0 0\nv 1 0 0\nf 1 2\n", report);
  EXPECT_TRUE(mesh.indices.empty());
  EXPECT_EQ(report.degenerate_triangles, 1u);
}

}  // namespace
}  // namespace twinray
