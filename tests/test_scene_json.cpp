// JSON scenes: every field reaches the Scene, relative paths resolve against the scene's folder, transforms
// are applied exactly, bare meshes get a framing camera, and the bundled scenes load.

#include "core/scene/json_reader.h"
#include "core/scene/json_scene.h"
#include "core/scene/mesh_scene.h"
#include "core/scene/scene_loader.h"
#include "core/util/input_error.h"
#include "scene_test_files.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <optional>
#include <string>

namespace twinray {
namespace {

const std::string kTetrahedronObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
const std::string kTrianglePly =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n2 0 0\n0 2 0\n3 0 1 2\n";

TEST(JsonScene, EveryFieldReachesTheScene) {
  testing::TempFolder folder;
  folder.write("tet.obj", kTetrahedronObj);
  folder.write("sky.hdr", "not decoded by the scene loader");
  const std::filesystem::path scene_file = folder.write("scene.json", R"({
    "comment": "all fields",
    "camera": {"position": [1, 2, 3], "look_at": [0, 0.5, 0], "up": [0, 0, 1], "fov": 45.5, "width": 320, "height": 200},
    "materials": {
      "white": {"type": "diffuse", "albedo": [0.25, 0.5, 0.75]},
      "chrome": {"type": "mirror", "reflectance": 0.5},
      "water": {"type": "glass", "ior": 1.33},
      "lamp": {"type": "emissive", "radiance": [10, 20, 30], "albedo": [0.1, 0.2, 0.3]}
    },
    "shapes": [
      {"type": "mesh", "file": "tet.obj", "material": "white", "name": "tet"},
      {"type": "triangles", "positions": [[0, 0, 5], [1, 0, 5], [0, 1, 5]], "indices": [[0, 1, 2]], "material": "lamp"},
      {"type": "sphere", "center": [1, 2, 3], "radius": 0.5, "material": "water", "name": "ball"},
      {"type": "sphere", "center": [-1, 0, 0], "radius": 2, "material": "chrome"}
    ],
    "environment": {"type": "image", "file": "sky.hdr", "rotation": 90, "scale": 2.5, "filter": "bilinear"},
    "render": {"spp": 128, "max_depth": 7, "seed": 18446744073709551615}
  })");
  const Scene scene = load_scene(scene_file);

  EXPECT_EQ(scene.source, scene_file);
  EXPECT_FALSE(scene.from_bare_mesh);
  EXPECT_EQ(scene.camera.position, glm::vec3(1, 2, 3));
  EXPECT_EQ(scene.camera.look_at, glm::vec3(0, 0.5f, 0));
  EXPECT_EQ(scene.camera.up, glm::vec3(0, 0, 1));
  EXPECT_EQ(scene.camera.vfov_deg, 45.5f);
  EXPECT_EQ(scene.camera.width, 320);
  EXPECT_EQ(scene.camera.height, 200);

  ASSERT_EQ(scene.materials.size(), 4u);  // in file order
  EXPECT_EQ(scene.materials[0].name, "white");
  EXPECT_EQ(scene.materials[0].type, MaterialType::Diffuse);
  EXPECT_EQ(scene.materials[0].albedo, glm::vec3(0.25f, 0.5f, 0.75f));
  EXPECT_EQ(scene.materials[1].name, "chrome");
  EXPECT_EQ(scene.materials[1].type, MaterialType::Mirror);
  EXPECT_EQ(scene.materials[1].reflectance, glm::vec3(0.5f));
  EXPECT_EQ(scene.materials[2].type, MaterialType::Glass);
  EXPECT_EQ(scene.materials[2].ior, 1.33f);
  EXPECT_EQ(scene.materials[3].type, MaterialType::Emissive);
  EXPECT_EQ(scene.materials[3].radiance, glm::vec3(10, 20, 30));
  EXPECT_EQ(scene.materials[3].albedo, glm::vec3(0.1f, 0.2f, 0.3f));

  ASSERT_EQ(scene.shapes.size(), 4u);
  EXPECT_EQ(scene.shapes[0].name, "tet");
  EXPECT_EQ(scene.shapes[0].kind, ShapeKind::Mesh);
  EXPECT_EQ(scene.shapes[0].material, 0u);
  EXPECT_EQ(scene.shapes[0].file, folder.path() / "tet.obj");
  EXPECT_EQ(scene.shapes[1].name, "shape 1");
  EXPECT_EQ(scene.shapes[1].material, 3u);
  EXPECT_TRUE(scene.shapes[1].file.empty());
  EXPECT_EQ(scene.shapes[2].kind, ShapeKind::Sphere);
  EXPECT_EQ(scene.shapes[2].name, "ball");
  EXPECT_EQ(scene.shapes[3].material, 1u);
  EXPECT_TRUE(scene.has_emitters());
  EXPECT_EQ(scene.material_of(1).name, "lamp");

  ASSERT_EQ(scene.geometry.meshes.size(), 2u);
  EXPECT_EQ(scene.geometry.meshes[0].geom_id, 0u);
  EXPECT_EQ(scene.geometry.meshes[0].triangle_count(), 4u);
  EXPECT_EQ(scene.geometry.meshes[1].geom_id, 1u);
  EXPECT_EQ(scene.geometry.meshes[1].positions[1], glm::vec3(1, 0, 5));
  ASSERT_EQ(scene.geometry.spheres.size(), 2u);
  EXPECT_EQ(scene.geometry.spheres[0].geom_id, 2u);
  EXPECT_EQ(scene.geometry.spheres[0].center, glm::vec3(1, 2, 3));
  EXPECT_EQ(scene.geometry.spheres[0].radius, 0.5f);
  EXPECT_EQ(scene.geometry.spheres[1].geom_id, 3u);
  EXPECT_EQ(scene.geometry.geom_id_end(), 4u);
  for (const TriangleMesh& m : scene.geometry.meshes) EXPECT_GT(m.positions.capacity(), m.positions.size());

  EXPECT_EQ(scene.environment.type, EnvironmentType::Image);
  EXPECT_EQ(scene.environment.image, folder.path() / "sky.hdr");
  EXPECT_EQ(scene.environment.rotation_deg, 90.0f);
  EXPECT_EQ(scene.environment.scale, 2.5f);
  EXPECT_EQ(scene.environment.filter, EnvironmentFilter::Bilinear);
  EXPECT_EQ(scene.render.spp, 128);
  EXPECT_EQ(scene.render.max_depth, 7);
  EXPECT_EQ(scene.render.seed, 18446744073709551615ull);
}

TEST(JsonScene, OptionalFieldsTakeDocumentedDefaults) {
  const Scene scene = parse_json_scene(R"({
    "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 30, "width": 1, "height": 65536},
    "materials": {"m": {"type": "mirror"}, "g": {"type": "glass"}, "e": {"type": "emissive", "radiance": 3}},
    "shapes": [],
    "environment": {"type": "constant", "radiance": [0.5, 0.25, 0]}
  })", "defaults.json");
  EXPECT_EQ(scene.camera.up, glm::vec3(0, 1, 0));
  EXPECT_EQ(scene.camera.height, 65536);
  EXPECT_EQ(scene.materials[0].reflectance, glm::vec3(1));
  EXPECT_EQ(scene.materials[1].ior, 1.5f);
  EXPECT_EQ(scene.materials[2].radiance, glm::vec3(3));
  EXPECT_EQ(scene.materials[2].albedo, glm::vec3(0));
  EXPECT_EQ(scene.environment.type, EnvironmentType::Constant);
  EXPECT_EQ(scene.environment.radiance, glm::vec3(0.5f, 0.25f, 0));
  EXPECT_EQ(scene.environment.filter, EnvironmentFilter::Nearest);  // the default lookup of image maps too
  EXPECT_EQ(scene.render.spp, 16);
  EXPECT_EQ(scene.render.max_depth, -1);
  EXPECT_EQ(scene.render.seed, 0u);
  EXPECT_FALSE(scene.has_emitters());  // defined but unused
}

TEST(JsonScene, RelativePathsResolveAgainstTheSceneFolder) {
  testing::TempFolder folder;
  folder.write("meshes/tri.ply", kTrianglePly);
  folder.write("scenes/local/tet.obj", kTetrahedronObj);
  const std::string absolute = (folder.path() / "meshes" / "tri.ply").string();
  const std::filesystem::path scene_file = folder.write("scenes/scene.json", R"({
    "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 30, "width": 8, "height": 8},
    "materials": {"white": {"type": "diffuse", "albedo": 0.5}},
    "shapes": [{"type": "mesh", "file": "../meshes/tri.ply", "material": "white"},
               {"type": "mesh", "file": "local/tet.obj", "material": "white"},
               {"type": "mesh", "file": ")" + absolute + R"(", "material": "white"}]
  })");
  const Scene scene = load_scene(scene_file);
  EXPECT_EQ(scene.shapes[0].file, folder.path() / "scenes" / "../meshes/tri.ply");
  EXPECT_EQ(scene.shapes[1].file, folder.path() / "scenes" / "local/tet.obj");
  EXPECT_EQ(scene.shapes[2].file, absolute);
  EXPECT_EQ(scene.geometry.triangle_count(), 1u + 4u + 1u);
}

Scene scene_with_shape(const std::string& shape) {
  return parse_json_scene(R"({
    "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 30, "width": 8, "height": 8},
    "materials": {"white": {"type": "diffuse", "albedo": 0.5}},
    "shapes": [)" + shape + R"(]})", "transform.json");
}

TEST(JsonScene, TransformScalesThenRotatesThenTranslates) {
  // (1,1,1) scaled by (2,3,4) is (2,3,4); 90 degrees about +z turns (x,y) into (-y,x): (-3,2,4); then +(1,2,3).
  // Every step is exact in double (cos 90 degrees ~ 6e-17 vanishes in the rounding), so equality is exact.
  const std::string tri = R"("positions": [[0, 0, 0], [1, 1, 1], [1, 0, 0]], "indices": [[0, 1, 2]], "material": "white")";
  const Scene srt = scene_with_shape(R"({"type": "triangles", )" + tri +
                                     R"(, "transform": {"scale": [2, 3, 4], "rotate": {"axis": [0, 0, 5], "angle": 90}, "translate": [1, 2, 3]}})");
  const TriangleMesh& mesh = srt.geometry.meshes.at(0);
  EXPECT_EQ(mesh.positions[0], glm::vec3(1, 2, 3));
  EXPECT_EQ(mesh.positions[1], glm::vec3(-2, 4, 7));
  EXPECT_EQ(mesh.positions[2], glm::vec3(1, 4, 3));
  EXPECT_EQ(mesh.indices[0], glm::uvec3(0, 1, 2));

  // The same transform as a row-major matrix.
  const Scene matrix = scene_with_shape(R"({"type": "triangles", )" + tri +
                                        R"(, "transform": {"matrix": [0, -3, 0, 1,  2, 0, 0, 2,  0, 0, 4, 3,  0, 0, 0, 1]}})");
  EXPECT_EQ(matrix.geometry.meshes.at(0).positions, mesh.positions);
}

TEST(JsonScene, MirroringTransformKeepsTheFrontSide) {
  // A triangle facing +z, mirrored in x: the winding is reversed so its geometric normal still faces +z.
  const Scene scene = scene_with_shape(R"({"type": "triangles", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
      "indices": [[0, 1, 2]], "material": "white", "transform": {"scale": [-1, 1, 1]}})");
  const TriangleMesh& mesh = scene.geometry.meshes.at(0);
  const glm::uvec3 t = mesh.indices.at(0);
  const glm::vec3 n = glm::cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]);
  EXPECT_GT(n.z, 0.0f);
  EXPECT_EQ(mesh.indices[0], glm::uvec3(0, 2, 1));
}

TEST(JsonScene, SphereTransformMovesCentreAndScalesRadius) {
  const Scene scene = scene_with_shape(R"({"type": "sphere", "center": [1, 0, 0], "radius": 0.5, "material": "white",
      "transform": {"scale": 4, "rotate": {"axis": [0, 1, 0], "angle": 180}, "translate": [0, 1, 0]}})");
  const Sphere& s = scene.geometry.spheres.at(0);
  // (1,0,0) * 4 = (4,0,0); 180 degrees about y: (-4,0,0) up to sin(pi) ~ 1.2e-16 * 4 in z; + (0,1,0).
  EXPECT_EQ(s.center.x, -4.0f);
  EXPECT_EQ(s.center.y, 1.0f);
  EXPECT_NEAR(s.center.z, 0.0f, 1e-15f);
  EXPECT_EQ(s.radius, 2.0f);
}

// A repeated key is an error at its own JSON pointer, however deep: array indices and escaped '/' and '~'
// (RFC 6901) included. The same key in two different objects is not a repeat.
TEST(JsonScene, RepeatedKeyIsAnErrorAtItsPointer) {
  const auto where = [](const std::string& text) {
    try {
      parse_json_text(text, "d.json");
    } catch (const InputError& e) {
      EXPECT_NE(e.message().find("duplicate key"), std::string::npos) << e.what();
      return e.where();
    }
    return std::string("no error");
  };
  EXPECT_EQ(where(R"({"a": 1, "a": 2})"), "/a");
  EXPECT_EQ(where(R"({"a": [1, {"b": 1}, {"c": 1, "d": [], "c": 2}]})"), "/a/2/c");
  EXPECT_EQ(where(R"({"x/y": {"k~": {"z": 0}, "k~": 1}})"), "/x~1y/k~0");
  EXPECT_EQ(where(R"([[{"": 0, "": 0}]])"), "/0/0/");
  EXPECT_EQ(where(R"({"a": {"k": 1}, "b": {"k": 1}, "k": [{"k": 1}, {"k": 2}]})"), "no error");
}

TEST(BareMeshScene, FramesTheBoundingSphereFromAbove) {
  testing::TempFolder folder;
  const std::filesystem::path mesh_file = folder.write("tet.obj", kTetrahedronObj);
  const Scene scene = load_scene(mesh_file);
  EXPECT_TRUE(scene.from_bare_mesh);
  // The mesh-viewer dressing: mid-grey mesh, darker ground plane, sky with a sun (docs/scene-format.md).
  ASSERT_EQ(scene.materials.size(), 2u);
  EXPECT_EQ(scene.materials[0].type, MaterialType::Diffuse);
  EXPECT_EQ(scene.materials[0].albedo, glm::vec3(0.5f));
  EXPECT_EQ(scene.materials[1].type, MaterialType::Diffuse);
  ASSERT_EQ(scene.shapes.size(), 2u);
  EXPECT_EQ(scene.shapes[0].file, mesh_file);
  EXPECT_EQ(scene.shapes[0].material, 0u);
  EXPECT_EQ(scene.shapes[1].material, 1u);
  EXPECT_EQ(scene.additions.size(), 3u);
  EXPECT_EQ(scene.environment.type, EnvironmentType::Image);
  ASSERT_TRUE(scene.environment.pixels);
  EXPECT_EQ(scene.environment.pixels->width, kSkyWidth);
  EXPECT_EQ(scene.camera.width, 640);
  EXPECT_EQ(scene.camera.height, 480);
  EXPECT_EQ(scene.camera.vfov_deg, 40.0f);
  EXPECT_EQ(scene.render.spp, 16);
  EXPECT_EQ(scene.render.max_depth, -1);
  EXPECT_EQ(scene.geometry.triangle_count(), 4u + 2u);

  // The ground plane: two triangles facing +Y, just below the mesh's lowest point (y = 0), wider than it.
  ASSERT_EQ(scene.geometry.meshes.size(), 2u);
  const TriangleMesh& ground = scene.geometry.meshes[1];
  EXPECT_EQ(ground.geom_id, 1u);
  const Bounds3 gb = ground.bounds();
  EXPECT_LT(gb.hi.y, 0.0f);
  EXPECT_GT(gb.hi.y, -1e-3f);
  EXPECT_EQ(gb.lo.y, gb.hi.y);
  EXPECT_LT(gb.lo.x, -1.0f);
  EXPECT_GT(gb.hi.z, 2.0f);
  for (const glm::uvec3& t : ground.indices) {
    const glm::vec3 n = glm::cross(ground.positions[t.y] - ground.positions[t.x], ground.positions[t.z] - ground.positions[t.x]);
    EXPECT_GT(n.y, 0.0f);
  }

  // Bounding box [0,1]^3: centre (0.5,0.5,0.5), bounding-sphere radius sqrt(3)/2; the sphere exactly fills
  // the 40 degree vertical field of view at distance r / sin(20 degrees).
  const glm::dvec3 center(0.5);
  EXPECT_EQ(scene.camera.look_at, glm::vec3(0.5f));
  const glm::dvec3 offset = glm::dvec3(scene.camera.position) - center;
  const double expected_distance = (std::sqrt(3.0) / 2.0) / std::sin(20.0 * std::numbers::pi / 180.0);
  EXPECT_NEAR(glm::length(offset), expected_distance, 1e-6 * expected_distance);  // float storage of position
  const glm::dvec3 direction = glm::normalize(offset);
  const glm::dvec3 expected_direction = glm::normalize(glm::dvec3(0.3, 0.4, 1.0));
  EXPECT_NEAR(glm::length(direction - expected_direction), 0.0, 1e-6);
}

TEST(BareMeshScene, FlatAndEmptyMeshesStillGetAFiniteCamera) {
  testing::TempFolder folder;
  // A unit quad in the z = 0 plane: a flat bounding box.
  const Scene flat = load_scene(folder.write("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"));
  EXPECT_EQ(flat.report.polygons_triangulated, 1u);
  const glm::vec3 offset = flat.camera.position - flat.camera.look_at;
  EXPECT_TRUE(std::isfinite(offset.x) && std::isfinite(offset.y) && std::isfinite(offset.z));
  EXPECT_NEAR(glm::length(offset), (std::sqrt(2.0) / 2.0) / std::sin(20.0 * std::numbers::pi / 180.0), 1e-5);

  // Only degenerate triangles: no geometry remains, the camera must still be usable.
  const Scene empty = load_scene(folder.write("line.obj", "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n"));
  EXPECT_EQ(empty.report.degenerate_triangles, 1u);
  EXPECT_EQ(empty.geometry.triangle_count(), 0u);
  const glm::vec3 p = empty.camera.position;
  EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
  EXPECT_GT(glm::length(p - empty.camera.look_at), 0.0f);
}

TEST(BundledScenes, CornellBoxMatchesTheReferenceSetup) {
  const Scene scene = load_scene(std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes" / "cornell-box.json");
  EXPECT_EQ(scene.camera.position, glm::vec3(0, 0, 3.9f));
  EXPECT_EQ(scene.camera.look_at, glm::vec3(0));
  EXPECT_EQ(scene.camera.vfov_deg, 39.3077f);
  EXPECT_EQ(scene.camera.width, 256);
  EXPECT_EQ(scene.camera.height, 256);
  EXPECT_EQ(scene.render.max_depth, -1);
  EXPECT_EQ(scene.shapes.size(), 8u);
  EXPECT_EQ(scene.geometry.triangle_count(), 36u);
  EXPECT_EQ(scene.report.degenerate_triangles, 0u);
  ASSERT_TRUE(scene.has_emitters());
  int emitters = 0;
  for (std::uint32_t id = 0; id < scene.shapes.size(); ++id) {
    const Material& m = scene.material_of(id);
    if (m.type != MaterialType::Emissive) continue;
    ++emitters;
    EXPECT_EQ(m.radiance, glm::vec3(18.387f, 13.9873f, 6.75357f));
    EXPECT_EQ(m.albedo, glm::vec3(0.885809f, 0.698859f, 0.666422f));
    // One-sided: the light must face down into the box.
    for (const TriangleMesh& mesh : scene.geometry.meshes) {
      if (mesh.geom_id != id) continue;
      for (const glm::uvec3& t : mesh.indices) {
        const glm::vec3 n = glm::cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]);
        EXPECT_LT(n.y, 0.0f);
      }
    }
  }
  EXPECT_EQ(emitters, 1);
}

TEST(BundledScenes, SpheresSceneHasEveryMaterialKind) {
  const Scene scene = load_scene(std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes" / "spheres.json");
  EXPECT_GE(scene.geometry.sphere_count(), 4u);
  bool seen[4] = {};
  for (std::uint32_t id = 0; id < scene.shapes.size(); ++id) seen[static_cast<int>(scene.material_of(id).type)] = true;
  EXPECT_TRUE(seen[0] && seen[1] && seen[2] && seen[3]);
  EXPECT_EQ(scene.environment.type, EnvironmentType::Constant);
}

// Scenes name files of the shared data folder as $TWINRAY_SHARED/...: the variable wins when set, otherwise a
// folder named `shared` beside an ancestor of the scene's folder is found, and without either the scene is
// rejected at the place that names the file.
class SharedDataPaths : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const char* old = std::getenv("TWINRAY_SHARED")) saved_ = old;
    ::unsetenv("TWINRAY_SHARED");
  }
  void TearDown() override {
    if (saved_) ::setenv("TWINRAY_SHARED", saved_->c_str(), 1);
    else ::unsetenv("TWINRAY_SHARED");
  }
  static constexpr const char* kTriangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  static constexpr const char* kScene = R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40, "width": 8, "height": 8},
    "materials": {"m": {"type": "diffuse", "albedo": 0.5}},
    "shapes": [{"type": "mesh", "file": "${TWINRAY_SHARED}/data/meshes/tri.obj", "material": "m"}]})";
  std::optional<std::string> saved_;
};

TEST_F(SharedDataPaths, TheVariableNamesTheFolder) {
  testing::TempFolder dir;
  dir.write("elsewhere/data/meshes/tri.obj", kTriangle);
  const std::filesystem::path scene_file = dir.write("repo/scenes/s.json", kScene);
  ::setenv("TWINRAY_SHARED", (dir.path() / "elsewhere").c_str(), 1);
  EXPECT_EQ(load_scene(scene_file).geometry.triangle_count(), 1u);
}

TEST_F(SharedDataPaths, ASharedFolderBesideTheRepositoryIsFound) {
  testing::TempFolder dir;
  dir.write("shared/data/meshes/tri.obj", kTriangle);
  const std::filesystem::path scene_file = dir.write("repo/scenes/s.json", kScene);
  EXPECT_EQ(load_scene(scene_file).geometry.triangle_count(), 1u);
}

TEST_F(SharedDataPaths, WithoutOneTheSceneIsRejectedAtThePlace) {
  testing::TempFolder dir;
  const std::filesystem::path scene_file = dir.write("repo/scenes/s.json", kScene);
  try {
    (void)load_scene(scene_file);
    FAIL() << "a scene naming a missing shared folder must be rejected";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/shapes/0/file"), std::string::npos) << what;
    EXPECT_NE(what.find("TWINRAY_SHARED"), std::string::npos) << what;
  }
}

// The shared third-party meshes: triangle counts from /work/shared/data/README.md. Degenerate triangles are
// dropped by the loader, so kept + dropped must equal the documented count.
TEST(SharedMeshes, TriangleCountsMatchTheDataReadme) {
  const char* shared = std::getenv("TWINRAY_SHARED");
  if (!shared || !std::filesystem::is_directory(std::filesystem::path(shared) / "data" / "meshes"))
    GTEST_SKIP() << "TWINRAY_SHARED is not set (or has no data/meshes): shared meshes not checked";
  const std::filesystem::path meshes = std::filesystem::path(shared) / "data" / "meshes";
  const struct {
    const char* file;
    std::size_t triangles;
  } expected[] = {{"stanford-bunny.obj", 69451}, {"dragon_100k.ply", 100000}, {"dabrovic_sponza.obj", 66447},
                  {"spot.obj", 5856},            {"teapot.obj", 6320}};
  for (const auto& e : expected) {
    const Scene scene = load_scene(meshes / e.file);
    // The mesh alone: the bare-mesh scene adds a two-triangle ground plane (geometry id 1).
    ASSERT_EQ(scene.geometry.meshes.size(), 2u) << e.file;
    EXPECT_EQ(scene.geometry.meshes[0].triangle_count() + scene.report.degenerate_triangles, e.triangles) << e.file;
    EXPECT_EQ(scene.report.nonfinite_triangles, 0u) << e.file;
  }
}

}  // namespace
}  // namespace twinray
