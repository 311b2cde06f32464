// Bad input, table-driven: every malformed file must fail with an InputError whose message names the file
// and the place in it (line, JSON pointer, vertex/face number) and says what is wrong. Never a crash, never
// a hang, never a huge allocation.

#include "core/scene/scene_loader.h"
#include "core/util/input_error.h"
#include "scene_test_files.h"
#include "ray_test_util.h"

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace twinray {
namespace {

using test::kNaN;

struct BadInputCase {
  std::string name;
  std::vector<std::pair<std::string, std::string>> files;  // relative path -> bytes
  std::string load;                                         // the file (or folder) passed to load_scene
  std::vector<std::string> expected;                        // substrings of what()
};

std::ostream& operator<<(std::ostream& os, const BadInputCase& c) { return os << c.name; }

// A valid scene around one shape (and optionally replaced camera / extra top-level entries).
std::string scene_json(const std::string& shapes, const std::string& camera_fields = R"("width": 64, "height": 48)",
                       const std::string& extra = "") {
  return R"({
  "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 40, )" + camera_fields + R"(},
  "materials": {"white": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
  "shapes": [)" + shapes + "]" + extra + "\n}\n";
}

std::string mesh_shape(const std::string& file) {
  return R"({"type": "mesh", "file": ")" + file + R"(", "material": "white"})";
}

const std::string kPlyHeaderLE =
    "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

std::string le_floats(std::initializer_list<float> values) {
  static_assert(std::endian::native == std::endian::little, "test data is written in native order");
  std::string out;
  for (float v : values) out.append(reinterpret_cast<const char*>(&v), sizeof v);
  return out;
}

std::string le_face(std::initializer_list<std::int32_t> corners) {
  std::string out(1, static_cast<char>(corners.size()));
  for (std::int32_t v : corners) out.append(reinterpret_cast<const char*>(&v), sizeof v);
  return out;
}

std::vector<BadInputCase> bad_inputs() {
  return {
      // ---- JSON syntax and values
      {"JsonSyntaxErrorReportsLineAndColumn",
       {{"scene.json", "{\n  \"camera\": {\n    \"fov\": 40,,\n  }\n}\n"}},
       "scene.json",
       {"scene.json:3:15:", "syntax error"}},
      {"EmptyJsonFile", {{"scene.json", ""}}, "scene.json", {"scene.json:1:1:", "unexpected end of input"}},
      {"JsonNumberTooLargeForDouble",
       {{"scene.json", scene_json(R"({"type": "sphere", "center": [0, 0,
   1e999], "radius": 1, "material": "white"})")}},
       "scene.json",
       {"scene.json:5:4:", "1e999", "out of range"}},
      {"JsonCoordinateOutOfFloatRange",
       {{"scene.json", scene_json(R"({"type": "triangles", "positions": [[0, 0, 0], [1, 0, 1e39], [0, 1, 0]],
          "indices": [[0, 1, 2]], "material": "white"})")}},
       "scene.json",
       {"scene.json: at /shapes/0/positions/1/2:", "out of float range"}},
      {"UnknownMaterial",
       {{"scene.json", scene_json(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "whte"})")}},
       "scene.json",
       {"scene.json: at /shapes/0/material:", "unknown material 'whte'", "white"}},
      {"UnknownKeySuggestsTheIntendedOne",
       {{"scene.json", scene_json("", R"("width": 64, "height": 48, "fvo": 30)")}},
       "scene.json",
       {"scene.json: at /camera/fvo:", "unknown key 'fvo'", "did you mean 'fov'"}},
      {"UnknownTopLevelKey",
       {{"scene.json", scene_json("", R"("width": 64, "height": 48)", R"(, "integrator": "path")")}},
       "scene.json",
       {"scene.json: at /integrator:", "unknown key 'integrator'"}},
      {"WrongType",
       {{"scene.json", scene_json("", R"("width": "640", "height": 48)")}},
       "scene.json",
       {"scene.json: at /camera/width:", "expected an integer, found a string"}},
      {"NonIntegerWidth",
       {{"scene.json", scene_json("", R"("width": 64.5, "height": 48)")}},
       "scene.json",
       {"at /camera/width:", "expected an integer"}},
      {"ZeroWidth",
       {{"scene.json", scene_json("", R"("width": 0, "height": 48)")}},
       "scene.json",
       {"scene.json: at /camera/width:", "out of range [1, 65536]"}},
      {"HugeHeight",
       {{"scene.json", scene_json("", R"("width": 64, "height": 100000)")}},
       "scene.json",
       {"at /camera/height:", "out of range"}},
      {"NegativeRadius",
       {{"scene.json", scene_json(R"({"type": "sphere", "center": [0, 0, 0], "radius": -1, "material": "white"})")}},
       "scene.json",
       {"scene.json: at /shapes/0/radius:", "radius must be positive"}},
      {"SphereRejectsNonUniformScale",
       {{"scene.json", scene_json(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "white",
          "transform": {"scale": [1, 2, 1]}})")}},
       "scene.json",
       {"at /shapes/0/transform:", "uniform scale"}},
      {"TriangleIndexOutOfRange",
       {{"scene.json", scene_json(R"({"type": "triangles", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
          "indices": [[0, 1, 3]], "material": "white"})")}},
       "scene.json",
       {"at /shapes/0/indices/0/2:", "index 3 out of range"}},
      {"MissingRequiredKey",
       {{"scene.json", scene_json(R"({"type": "sphere", "center": [0, 0, 0], "material": "white"})")}},
       "scene.json",
       {"at /shapes/0:", "missing required key 'radius'"}},
      {"FovOutOfRange",
       {{"scene.json", R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 180, "width": 4, "height": 4},
          "materials": {}, "shapes": []})"}},
       "scene.json",
       {"at /camera/fov:", "(0, 180)"}},
      {"LookAtEqualsPosition",
       {{"scene.json", R"({"camera": {"position": [1, 1, 1], "look_at": [1, 1, 1], "fov": 40, "width": 4, "height": 4},
          "materials": {}, "shapes": []})"}},
       "scene.json",
       {"at /camera/look_at:", "must differ"}},
      {"NegativeAlbedo",
       {{"scene.json", R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 40, "width": 4, "height": 4},
          "materials": {"bad": {"type": "diffuse", "albedo": [0.5, -0.1, 0.5]}}, "shapes": []})"}},
       "scene.json",
       {"at /materials/bad/albedo/1:", "non-negative"}},
      {"ZeroMaxDepth",
       {{"scene.json", scene_json("", R"("width": 64, "height": 48)", R"(, "render": {"max_depth": 0})")}},
       "scene.json",
       {"at /render/max_depth:", "-1 (unlimited) or at least 1"}},
      {"UnknownMaterialType",
       {{"scene.json", R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 40, "width": 4, "height": 4},
          "materials": {"m": {"type": "metal"}}, "shapes": []})"}},
       "scene.json",
       {"at /materials/m/type:", "unknown material type 'metal'"}},
      {"MissingEnvironmentImage",
       {{"scene.json", scene_json("", R"("width": 64, "height": 48)", R"(, "environment": {"type": "image", "file": "sky.hdr"})")}},
       "scene.json",
       {"sky.hdr: file not found", "/environment/file"}},

      // ---- files that are not there or not files
      {"MissingSceneFile", {}, "nothere.json", {"nothere.json: file not found"}},
      {"MissingMeshFile",
       {{"scene.json", scene_json(mesh_shape("meshes/bunny.obj"))}},
       "scene.json",
       {"bunny.obj: file not found", "/shapes/0/file", "scene.json"}},
      {"DirectoryInsteadOfMeshFile",
       {{"scene.json", scene_json(mesh_shape("meshes.obj")), }, {"meshes.obj/keep", ""}},
       "scene.json",
       {"meshes.obj: is a directory", "/shapes/0/file"}},
      {"DirectoryInsteadOfScene", {{"folder.json/keep", ""}}, "folder.json", {"folder.json: is a directory"}},
      {"UnsupportedSceneType", {{"scene.stl", "solid x\n"}}, "scene.stl", {"scene.stl:", "unknown scene file type '.stl'"}},

      // ---- OBJ
      {"ObjFaceIndexOutOfRange",
       {{"bad.obj", "# three vertices\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"}},
       "bad.obj",
       {"bad.obj:5:", "face index 7 out of range (file has 3 vertices)"}},
      {"ObjRelativeIndexBeforeFirstVertex",
       {{"bad.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n"}},
       "bad.obj",
       {"bad.obj:3:", "relative face index -3 out of range"}},
      {"ObjFaceIndexZero", {{"bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"}}, "bad.obj", {"bad.obj:4:", "index 0"}},
      {"ObjNaNCoordinate",
       {{"bad.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n"}},
       "bad.obj",
       {"bad.obj:2:", "non-finite coordinate 'nan'"}},
      {"ObjInfCoordinate", {{"bad.obj", "v 0 0 inf\n"}}, "bad.obj", {"bad.obj:1:", "non-finite"}},
      {"ObjOverflowingCoordinate", {{"bad.obj", "v 0 0 0\nv 1e39 0 0\n"}}, "bad.obj", {"bad.obj:2:", "out of float range"}},
      {"ObjGarbageCoordinate", {{"bad.obj", "v 0 0 0\nv 1 2 3x\n"}}, "bad.obj", {"bad.obj:2:", "invalid coordinate '3x'"}},
      {"ObjMissingCoordinate", {{"bad.obj", "v 0 0\n"}}, "bad.obj", {"bad.obj:1:", "three coordinates"}},
      {"ObjErrorInReferencedMesh",
       {{"scene.json", scene_json(mesh_shape("m.obj"))}, {"m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"}},
       "scene.json",
       {"m.obj:4:", "face index 4 out of range", "/shapes/0/file"}},

      // ---- PLY
      {"PlyTruncatedBinary",
       {{"bad.ply", kPlyHeaderLE + le_floats({0, 0, 0, 1, 0, 0, 0, 1})}},
       "bad.ply",
       {"bad.ply:3:", "truncated"}},  // caught by the header's size check, before reading
      {"PlyTruncatedInFaceList",
       {{"bad.ply", kPlyHeaderLE + le_floats({0, 0, 0, 1, 0, 0, 0, 1, 0}) + le_face({0, 1, 2}).substr(0, 7)}},
       "bad.ply",
       {"bad.ply: at face 0:", "truncated"}},
      {"PlyHugeVertexCount",
       {{"bad.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\n"
                    "property float y\nproperty float z\nend_header\n" + le_floats({0, 0, 0})}},
       "bad.ply",
       {"bad.ply:3:", "1000000000000", "cannot hold"}},
      {"PlyHugeAsciiCount",
       {{"bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 4000000000\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"}},
       "bad.ply",
       {"bad.ply:7:", "4000000000"}},
      {"PlyNaNBinary",
       {{"bad.ply", kPlyHeaderLE + le_floats({0, 0, 0, 1, kNaN, 0, 0, 1, 0}) + le_face({0, 1, 2})}},
       "bad.ply",
       {"bad.ply: at vertex 1:", "non-finite"}},
      {"PlyNaNAscii",
       {{"bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "end_header\n0 0 0\n1 0 0\n0 nan 0\n"}},
       "bad.ply",
       {"bad.ply:10:", "non-finite"}},
      {"PlyIndexOutOfRangeBinary",
       {{"bad.ply", kPlyHeaderLE + le_floats({0, 0, 0, 1, 0, 0, 0, 1, 0}) + le_face({0, 1, 3})}},
       "bad.ply",
       {"bad.ply: at face 0:", "vertex index 3 out of range (file has 3 vertices)"}},
      {"PlyNegativeIndexAscii",
       {{"bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"}},
       "bad.ply",
       {"bad.ply:13:", "vertex index -1 out of range"}},
      {"PlyAsciiTooFewValues",
       {{"bad.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                    "end_header\n0.0 0.0 0.0\n1.0 0.0\n"}},
       "bad.ply",
       {"bad.ply:9:", "missing property 'z'"}},
      {"PlyNotAPlyFile", {{"bad.ply", "solid cube\n"}}, "bad.ply", {"bad.ply:1:", "not a PLY file"}},
      {"PlyBadVersion", {{"bad.ply", "ply\nformat ascii 2.0\nend_header\n"}}, "bad.ply", {"bad.ply:2:", "version"}},
      {"PlyUnknownType",
       {{"bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n"}},
       "bad.ply",
       {"bad.ply:4:", "unknown PLY property type 'float128'"}},
      {"PlyNoEndHeader", {{"bad.ply", "ply\nformat ascii 1.0\nelement vertex 0\n"}}, "bad.ply", {"bad.ply:", "end_header"}},
      {"PlyMissingZ",
       {{"bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n"}},
       "bad.ply",
       {"bad.ply:3:", "no scalar property 'z'"}},
  };
}

class BadInput : public ::testing::TestWithParam<BadInputCase> {};

TEST_P(BadInput, FailsWithFileLocationAndReason) {
  const BadInputCase& c = GetParam();
  testing::TempFolder folder;
  for (const auto& [name, bytes] : c.files) folder.write(name, bytes);
  try {
    (void)load_scene(folder.path() / c.load);
    FAIL() << "loaded without error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    for (const std::string& part : c.expected) EXPECT_NE(what.find(part), std::string::npos) << "missing '" << part << "' in: " << what;
    EXPECT_EQ(what.rfind(folder.path().string(), 0), 0u) << "message should start with the file path: " << what;
  }
}

INSTANTIATE_TEST_SUITE_P(Loaders, BadInput, ::testing::ValuesIn(bad_inputs()),
                         [](const ::testing::TestParamInfo<BadInputCase>& param_info) { return param_info.param.name; });

}  // namespace
}  // namespace twinray
