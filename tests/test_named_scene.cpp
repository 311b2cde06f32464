// Scenes by name (harness/scenes/named_scene.h): what suites and `twinray trace` load.

#include "core/util/input_error.h"
#include "harness/scenes/named_scene.h"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace twinray {
namespace {

TEST(NamedScene, ProceduralScenesHaveTheDocumentedSizes) {
  EXPECT_EQ(load_named_scene("procedural:empty").geometry.primitive_count(), 0u);
  EXPECT_EQ(load_named_scene("procedural:triangle").geometry.triangle_count(), 1u);
  EXPECT_EQ(load_named_scene("procedural:identical-triangles:300").geometry.triangle_count(), 300u);
  EXPECT_EQ(load_named_scene("procedural:grid:3:5").geometry.triangle_count(), 30u);
  EXPECT_EQ(load_named_scene("procedural:sphere-mesh:2").geometry.triangle_count(), 320u);  // 20 * 4^2
  EXPECT_EQ(load_named_scene("procedural:box:-1:1").geometry.triangle_count(), 6u * 2u * 2u * 2u);
  EXPECT_EQ(load_named_scene("procedural:spheres:7:1").geometry.sphere_count(), 7u);
  EXPECT_EQ(load_named_scene("procedural:sphere-sizes").geometry.sphere_count(), 5u);
  const Scene dup = load_named_scene("procedural:duplicates:10:2");
  ASSERT_EQ(dup.geometry.meshes.size(), 2u);
  EXPECT_EQ(dup.geometry.meshes[0].triangle_count(), 20u);
  EXPECT_EQ(dup.geometry.meshes[1].indices, dup.geometry.meshes[0].indices);
  // The reversed duplicates: mesh 1 lists mesh 0's triangles backwards, each with its vertices in order, so
  // mesh 0's triangle k is mesh 1's 2n - 1 - k (and n - 1 - k): a lower prim_id for k >= n / 2.
  const Scene rev = load_named_scene("procedural:duplicates-reversed:10:2");
  ASSERT_EQ(rev.geometry.meshes.size(), 2u);
  ASSERT_EQ(rev.geometry.meshes[1].indices.size(), 20u);
  EXPECT_EQ(rev.geometry.meshes[0].indices, dup.geometry.meshes[0].indices);
  for (std::size_t k = 0; k < 20; ++k)
    EXPECT_EQ(rev.geometry.meshes[1].indices[19 - k], rev.geometry.meshes[0].indices[k]) << k;
  // The box's triangles listed 24 times each in one mesh, shuffled: every triangle of procedural:box is there 24
  // times, and the order is not the box's (the copy with the lowest prim_id is not always the first listed).
  const Scene box = load_named_scene("procedural:box:-1:1");
  const Scene dbox = load_named_scene("procedural:duplicates-box:-1:1:24:1");
  ASSERT_EQ(dbox.geometry.meshes.size(), 1u);
  ASSERT_EQ(dbox.geometry.meshes[0].indices.size(), 24u * box.geometry.meshes[0].indices.size());
  for (const glm::uvec3& t : box.geometry.meshes[0].indices)
    EXPECT_EQ(std::count(dbox.geometry.meshes[0].indices.begin(), dbox.geometry.meshes[0].indices.end(), t), 24);
  EXPECT_NE(dbox.geometry.meshes[0].indices[1], dbox.geometry.meshes[0].indices[0]);
  EXPECT_EQ(load_named_scene("procedural:duplicates-box:-1:1:24:1").geometry.meshes[0].indices,
            dbox.geometry.meshes[0].indices);
  // Every scene has a shape per geometry id and a material, like a loaded scene.
  EXPECT_EQ(dup.shapes.size(), 2u);
  EXPECT_FALSE(dup.materials.empty());
}

TEST(NamedScene, ProceduralScenesAreDeterministic) {
  const Scene a = load_named_scene("procedural:soup:100:9"), b = load_named_scene("procedural:soup:100:9");
  ASSERT_EQ(a.geometry.meshes[0].positions.size(), b.geometry.meshes[0].positions.size());
  EXPECT_EQ(std::memcmp(a.geometry.meshes[0].positions.data(), b.geometry.meshes[0].positions.data(),
                        a.geometry.meshes[0].positions.size() * sizeof(glm::vec3)),
            0);
  const Scene far = load_named_scene("procedural:sphere-mesh:1:100:0:0:2");
  EXPECT_NEAR(far.geometry.bounds().center().x, 100.0f, 1e-3f);
}

// The deep-tree scene: level j of L holds ceil(1.15^(L - 1 - j)) triangles in each of its two cones (and the
// innermost three one more, across the tunnel), at
// distance about 2^(36 - 1.5 j) from the origin, the innermost (j = 48) at about 2^-36.
TEST(NamedScene, NestHasItsLevelsAtTheDocumentedScales) {
  const Scene nest = load_named_scene("procedural:nest:49:1");
  std::size_t expected = 0;
  double count = 1.0;
  for (int j = 0; j < 49; ++j, count *= 1.15) expected += static_cast<std::size_t>(std::ceil(count));
  // Two cones, and in each the innermost three levels also hold a triangle across the tunnel.
  EXPECT_EQ(nest.geometry.triangle_count(), 2 * (expected + 3));
  float nearest = INFINITY, farthest = 0.0f;
  for (const glm::vec3& p : nest.geometry.meshes[0].positions) {
    nearest = std::min(nearest, glm::length(p));
    farthest = std::max(farthest, glm::length(p));
  }
  // Distances are scale * (0.7..1) * (0.9..1.1) * |(0.6..1.4)^3|: within [0.37, 2.7] of the level's scale.
  EXPECT_GE(nearest, 0.37f * std::ldexp(1.0f, -36));
  EXPECT_LE(nearest, 2.7f * std::ldexp(1.0f, -36));
  EXPECT_GE(farthest, 0.37f * std::ldexp(1.0f, 36));
  EXPECT_LE(farthest, 2.7f * std::ldexp(1.0f, 36));
  EXPECT_EQ(load_named_scene("procedural:nest:1:1").geometry.triangle_count(), 4u);
  // One cone, around (-1, -1, -1): half the triangles, every vertex in the negative octant.
  const Scene one = load_named_scene("procedural:nest:49:1:-1:-1:-1");
  EXPECT_EQ(one.geometry.triangle_count(), expected + 3);
  for (const glm::vec3& p : one.geometry.meshes[0].positions) {
    EXPECT_LT(p.x, 0.0f);
    EXPECT_LT(p.y, 0.0f);
    EXPECT_LT(p.z, 0.0f);
  }
}

// The capped nest (CAP 1): the one cone's triangles plus one across its tunnel at 2^38 along the axis, and no
// triangle of the innermost levels but their small ones crosses the tunnel, so a ray along the axis a little
// off the small ones reaches the cap.
TEST(NamedScene, CappedNestHasOneMoreTriangleAcrossTheTunnel) {
  const Scene capped = load_named_scene("procedural:nest:49:1:1:1:1:1");
  const Scene plain = load_named_scene("procedural:nest:49:1:1:1:1");
  EXPECT_EQ(capped.geometry.triangle_count(), plain.geometry.triangle_count() + 1);
  const TriangleMesh& m = capped.geometry.meshes[0];
  const glm::uvec3 cap = m.indices.back();
  const glm::vec3 centre = (m.positions[cap[0]] + m.positions[cap[1]] + m.positions[cap[2]]) / 3.0f;
  EXPECT_NEAR(centre.x / std::ldexp(1.0f, 38), 1.0 / std::sqrt(3.0), 1e-5);
  EXPECT_NEAR(centre.x, centre.y, 1e-6 * centre.x);
  EXPECT_NEAR(centre.x, centre.z, 1e-6 * centre.x);
  EXPECT_THROW(load_named_scene("procedural:nest:49:1:1:1:1:2"), InputError);
  EXPECT_THROW(load_named_scene("procedural:nest:49:1:1:1"), InputError);
}

TEST(NamedScene, BadNamesAreInputErrorsNamingTheScene) {
  for (const char* bad : {"procedural:nothing", "procedural:soup:10", "procedural:soup:-3:1", "procedural:grid:2:x",
                          "procedural:sphere-mesh:12", "procedural:box:3:1", "procedural:empty:1",
                          "procedural:sphere-mesh:1:0:0:0:-1", "procedural:nest:50:1", "procedural:nest:0:1",
                          "procedural:nest:49:1:0:1:1", "procedural:nest:49:1:-1:-1", "procedural:nest:49:1:1:2:1",
                          "no/such/scene.json"}) {
    try {
      load_named_scene(bad);
      ADD_FAILURE() << bad << " loaded";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

TEST(NamedScene, FilesResolveAgainstTheBaseAndBecomeAbsolute) {
  const std::filesystem::path scenes = std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes";
  EXPECT_EQ(load_named_scene("cornell-box.json", scenes).geometry.triangle_count(), 36u);
  const std::string portable = portable_scene_name("cornell-box.json", scenes);
  EXPECT_TRUE(std::filesystem::path(portable).is_absolute()) << portable;
  EXPECT_EQ(portable_scene_name("procedural:grid:2:2", scenes), "procedural:grid:2:2");
  EXPECT_EQ(portable_scene_name("$TWINRAY_SHARED/data/meshes/bunny.obj", scenes), "$TWINRAY_SHARED/data/meshes/bunny.obj");
}

}  // namespace
}  // namespace twinray
