// The end-to-end bad-input table (issue 5, part 2): every input path of the `twinray` program (scene JSON,
// OBJ, PLY, HDR/EXR environment maps, command-line values, unreadable and unwritable paths, a folder
// where a file is expected) fed malformed input through the real binary. Each row must give:
//   - exit code 2 (bad input), never a crash (a signal shows as 128 + N) or a hang;
//   - a message naming the file and the place in it (line[:column], JSON pointer) or the option;
//   - no output file and no temporary left behind: the folder's listing is unchanged.
// The loader-level table (tests/test_bad_input_loaders.cpp) checks the exceptions in-process; this one
// checks what a user sees. Rows already covered by tests/test_cli_contract.cpp are not repeated.

#include "cli_runner.h"
#include "core/image/image.h"
#include "core/image/image_io.h"

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <string>
#include <vector>

namespace twinray::testing {
namespace {

struct Row {
  std::string name;
  std::vector<std::pair<std::string, std::string>> files;  // written into the row's folder
  std::string args;                                        // {dir} is replaced by the folder
  std::vector<std::string> expected;                       // substrings of the output
};

std::ostream& operator<<(std::ostream& os, const Row& r) { return os << r.name; }

std::string scene(const std::string& shape, const std::string& camera = R"("width": 8, "height": 8)",
                  const std::string& extra = "") {
  return R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 40, )" + camera +
         R"(},
 "materials": {"w": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
 "shapes": [)" + shape + "]" + extra + "}\n";
}
const std::string kSphere = R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "w"})";
std::string mesh_file(const std::string& f) { return R"({"type": "mesh", "file": ")" + f + R"(", "material": "w"})"; }
std::string env_image(const std::string& f) {
  return R"(, "environment": {"type": "image", "file": ")" + f + R"("})";
}
const std::string kTriObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
const std::string kPlyAsciiHead =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
const std::string kPlyBinaryHead =
    "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

// Render rows write nothing when they fail: out.exr and out.json must not appear.
std::string render(const std::string& input, const std::string& more = "") {
  return "render " + input + " -o {dir}/out.exr --json {dir}/out.json " + more;
}

std::vector<Row> rows() {
  const std::string ok = scene(kSphere);
  return {
      // --- scene JSON ---
      {"json_truncated", {{"s.json", ok.substr(0, 60)}}, render("{dir}/s.json"), {"s.json:1:", "JSON syntax error"}},
      {"json_wrong_type", {{"s.json", scene(R"({"type": "sphere", "center": [0, 0, 0], "radius": "big", "material": "w"})")}},
       render("{dir}/s.json"), {"s.json: at /shapes/0/radius", "number"}},
      {"json_duplicate_key", {{"s.json", scene(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "radius": 2, "material": "w"})")}},
       render("{dir}/s.json"), {"s.json: at /shapes/0/radius", "duplicate key 'radius'"}},
      {"json_number_overflow_inf", {{"s.json", scene(R"({"type": "sphere", "center": [0, 1e999, 0], "radius": 1, "material": "w"})")}},
       render("{dir}/s.json"), {"s.json:", "1e999"}},
      {"json_negative_radius", {{"s.json", scene(R"({"type": "sphere", "center": [0, 0, 0], "radius": -1, "material": "w"})")}},
       render("{dir}/s.json"), {"s.json: at /shapes/0/radius"}},
      {"json_zero_width", {{"s.json", scene(kSphere, R"("width": 0, "height": 8)")}}, render("{dir}/s.json"),
       {"s.json: at /camera/width"}},
      {"json_negative_height", {{"s.json", scene(kSphere, R"("width": 8, "height": -8)")}}, render("{dir}/s.json"),
       {"s.json: at /camera/height"}},
      {"json_huge_resolution", {{"s.json", scene(kSphere, R"("width": 100000000, "height": 8)")}},
       render("{dir}/s.json"), {"s.json: at /camera/width"}},
      {"json_zero_spp", {{"s.json", scene(kSphere, R"("width": 8, "height": 8)", R"(, "render": {"spp": 0})")}},
       render("{dir}/s.json"), {"s.json: at /render/spp"}},
      {"json_zero_depth", {{"s.json", scene(kSphere, R"("width": 8, "height": 8)", R"(, "render": {"max_depth": 0})")}},
       render("{dir}/s.json"), {"s.json: at /render/max_depth"}},
      {"json_unknown_material", {{"s.json", scene(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "gold"})")}},
       render("{dir}/s.json"), {"s.json: at /shapes/0/material", "gold"}},
      {"json_inline_index_out_of_range",
       {{"s.json", scene(R"({"type": "triangles", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "indices": [[0, 1, 7]], "material": "w"})")}},
       render("{dir}/s.json"), {"s.json: at /shapes/0/indices"}},
      {"json_mesh_is_a_folder", {{"m.obj/keep", ""}, {"s.json", scene(mesh_file("m.obj"))}}, render("{dir}/s.json"),
       {"m.obj", "directory", "/shapes/0/file"}},
      {"json_mesh_missing", {{"s.json", scene(mesh_file("missing.obj"))}}, render("{dir}/s.json"),
       {"missing.obj", "/shapes/0/file"}},
      // --- OBJ ---
      {"obj_index_out_of_range", {{"m.obj", kTriObj + "f 1 2 9\n"}}, render("{dir}/m.obj"), {"m.obj:4", "9"}},
      {"obj_zero_index", {{"m.obj", kTriObj + "f 0 1 2\n"}}, render("{dir}/m.obj"), {"m.obj:4"}},
      {"obj_huge_index", {{"m.obj", kTriObj + "f 1 2 99999999999999999999\n"}}, render("{dir}/m.obj"), {"m.obj:4"}},
      {"obj_nan_coordinate", {{"m.obj", "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"}}, render("{dir}/m.obj"),
       {"m.obj:1", "non-finite"}},
      {"obj_inf_coordinate", {{"m.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n"}}, render("{dir}/m.obj"), {"m.obj:2"}},
      {"obj_wrong_type", {{"m.obj", "v 0 zero 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"}}, render("{dir}/m.obj"), {"m.obj:1"}},
      {"obj_referenced_from_scene", {{"m.obj", kTriObj + "f 1 2 -4\n"}, {"s.json", scene(mesh_file("m.obj"))}},
       render("{dir}/s.json"), {"m.obj:4", "s.json"}},
      // --- PLY ---
      {"ply_huge_count",
       {{"m.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                  "property float y\nproperty float z\nend_header\n"}},
       render("{dir}/m.ply"), {"m.ply:3", "4000000000"}},
      {"ply_truncated_binary", {{"m.ply", kPlyBinaryHead + std::string(10, '\0')}}, render("{dir}/m.ply"), {"m.ply"}},
      {"ply_index_out_of_range", {{"m.ply", kPlyAsciiHead + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"}}, render("{dir}/m.ply"),
       {"m.ply:", "3"}},
      {"ply_nan_vertex", {{"m.ply", kPlyAsciiHead + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n"}}, render("{dir}/m.ply"),
       {"m.ply:"}},
      {"ply_unknown_format", {{"m.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n"}}, render("{dir}/m.ply"),
       {"m.ply:2"}},
      {"ply_truncated_header", {{"m.ply", "ply\nformat ascii 1.0\nelement vertex 3\nprop"}}, render("{dir}/m.ply"),
       {"m.ply"}},
      // --- HDR / EXR environment maps ---
      {"hdr_truncated", {{"e.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16 +X 32\n\x01\x02"}, {"s.json", scene(kSphere, R"("width": 8, "height": 8)", env_image("e.hdr"))}},
       render("{dir}/s.json"), {"e.hdr"}},
      {"exr_not_an_image", {{"e.exr", "not an exr\n"}, {"s.json", scene(kSphere, R"("width": 8, "height": 8)", env_image("e.exr"))}},
       render("{dir}/s.json"), {"e.exr"}},
      {"env_is_a_folder", {{"e.hdr/keep", ""}, {"s.json", scene(kSphere, R"("width": 8, "height": 8)", env_image("e.hdr"))}},
       render("{dir}/s.json"), {"e.hdr", "directory"}},
      {"env_unknown_filter",
       {{"e.hdr", "read only after the scene parses"},
        {"s.json", scene(kSphere, R"("width": 8, "height": 8)",
                         R"(, "environment": {"type": "image", "file": "e.hdr", "filter": "cubic"})")}},
       render("{dir}/s.json"), {"s.json", "/environment/filter", "cubic", "nearest or bilinear"}},
      {"env_flag_missing_file", {{"s.json", ok}}, render("{dir}/s.json", "--env {dir}/missing.hdr"), {"missing.hdr"}},
      {"env_flag_truncated", {{"s.json", ok}, {"e.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16 +X 32\n"}},
       render("{dir}/s.json", "--env {dir}/e.hdr"), {"e.hdr"}},
      // --- command-line values ---
      {"spp_zero", {{"s.json", ok}}, render("{dir}/s.json", "--spp 0"), {"--spp"}},
      {"spp_negative", {{"s.json", ok}}, render("{dir}/s.json", "--spp -3"), {"spp"}},
      {"spp_not_a_number", {{"s.json", ok}}, render("{dir}/s.json", "--spp many"), {"spp"}},
      {"spp_huge", {{"s.json", ok}}, render("{dir}/s.json", "--spp 99999999999999999999"), {"spp"}},
      {"depth_zero", {{"s.json", ok}}, render("{dir}/s.json", "--max-depth 0"), {"--max-depth"}},
      {"depth_negative", {{"s.json", ok}}, render("{dir}/s.json", "--max-depth -2"), {"--max-depth"}},
      {"rr_depth_zero", {{"s.json", ok}}, render("{dir}/s.json", "--rr-depth 0"), {"--rr-depth"}},
      {"time_negative", {{"s.json", ok}}, render("{dir}/s.json", "--time -1"), {"--time"}},
      {"time_nan", {{"s.json", ok}}, render("{dir}/s.json", "--time nan"), {"--time"}},
      {"threads_negative", {{"s.json", ok}}, render("{dir}/s.json", "--threads -1"), {"--threads"}},
      {"stress_effort_zero", {}, "stress --effort 0 --json {dir}/out.json", {"--effort"}},
      {"stress_effort_nan", {}, "stress --effort nan --json {dir}/out.json", {"--effort"}},
      {"stress_unknown_case", {}, "stress --case no-such-case --json {dir}/out.json", {"no-such-case"}},
      {"stress_unknown_backend", {}, "stress --backends bvh,optix --json {dir}/out.json", {"optix"}},
      // --- paths ---
      {"scene_is_a_folder", {{"s.json/keep", ""}}, render("{dir}/s.json"), {"s.json"}},
      {"output_under_a_file", {{"s.json", ok}, {"f.txt", "x"}}, "render {dir}/s.json --spp 1 -o {dir}/f.txt/out.exr",
       {"out.exr"}},
      {"output_in_missing_folder", {{"s.json", ok}}, "render {dir}/s.json --spp 1 -o {dir}/nofolder/out.exr",
       {"nofolder"}},
      {"output_is_a_folder", {{"s.json", ok}, {"o.exr/keep", ""}}, "render {dir}/s.json --spp 1 -o {dir}/o.exr",
       {"o.exr"}},
      {"stress_json_in_missing_folder", {},
       "stress --case nonfinite-vertices --backends bvh --json {dir}/nofolder/s.json", {"s.json"}},
  };
}

std::string substitute(std::string s, const std::filesystem::path& dir) {
  for (std::size_t at; (at = s.find("{dir}")) != std::string::npos;) s.replace(at, 5, "'" + dir.string() + "'");
  return s;
}

std::set<std::string> listing(const std::filesystem::path& dir) {
  std::set<std::string> out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    out.insert(std::filesystem::relative(e.path(), dir).string());
  return out;
}

std::filesystem::path write_files(const std::string& name, const std::vector<std::pair<std::string, std::string>>& files) {
  const std::filesystem::path dir = scratch_dir("bad-table-" + name);
  for (const auto& [rel, bytes] : files) {
    const std::filesystem::path p = dir / rel;
    std::filesystem::create_directories(p.parent_path());
    if (p.filename() == "keep") continue;  // the parent folder is the point
    std::ofstream(p, std::ios::binary) << bytes;
  }
  return dir;
}

void expect_clean_failure(const CommandResult& r, const std::vector<std::string>& expected,
                          const std::set<std::string>& before, const std::filesystem::path& dir) {
  EXPECT_EQ(r.exit_code, 2) << r.output;
  for (const std::string& s : expected) EXPECT_NE(r.output.find(s), std::string::npos) << "missing '" << s << "' in:\n" << r.output;
  EXPECT_EQ(listing(dir), before) << "output or temporary files left behind";
}

class BadInputTable : public ::testing::TestWithParam<Row> {};

TEST_P(BadInputTable, ExitsTwoWithLocationAndLeavesNothing) {
  const Row& row = GetParam();
  const std::filesystem::path dir = write_files(row.name, row.files);
  const std::set<std::string> before = listing(dir);
  const CommandResult r = run_twinray(substitute(row.args, dir));
  expect_clean_failure(r, row.expected, before, dir);
  std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(AllInputs, BadInputTable, ::testing::ValuesIn(rows()),
                         [](const ::testing::TestParamInfo<Row>& row) { return row.param.name; });

// Environment maps with non-finite or negative texels, written as real EXR files.
TEST(BadInputTableImages, NonFiniteAndNegativeTexelsAreRejectedWithTheirPosition) {
  const struct {
    const char* name;
    float value;
  } cases[] = {{"nan", std::numeric_limits<float>::quiet_NaN()},
               {"inf", std::numeric_limits<float>::infinity()},
               {"negative", -1.0f}};
  for (const auto& c : cases) {
    const std::filesystem::path dir = write_files(std::string("texel-") + c.name, {{"s.json", scene(kSphere)}});
    Image img(8, 4, 3);
    for (float& v : img.data) v = 1.0f;
    img.at(5, 2, 1) = c.value;
    write_exr(dir / "e.exr", img);
    const std::set<std::string> before = listing(dir);
    const CommandResult r = run_twinray(substitute(render("{dir}/s.json", "--env {dir}/e.exr"), dir));
    expect_clean_failure(r, {"e.exr", "texel"}, before, dir);
    std::filesystem::remove_all(dir);
  }
}

// An unreadable scene. chmod 000 does not deny root, so when the tests run as root the program is run as
// the unprivileged user 65534 (nobody) through setpriv; the folder is world-readable, the file is not.
TEST(BadInputTablePaths, UnreadableSceneFailsWithPermissionMessage) {
  const std::filesystem::path dir = write_files("unreadable", {{"s.json", scene(kSphere)}});
  std::filesystem::permissions(dir, std::filesystem::perms::all);
  ::chmod((dir / "s.json").c_str(), 0);
  std::string prefix;
  if (::geteuid() == 0) {
    if (std::system("command -v setpriv >/dev/null 2>&1") != 0)
      GTEST_SKIP() << "running as root without setpriv: chmod 000 cannot make a file unreadable for root";
    prefix = "setpriv --reuid=65534 --regid=65534 --clear-groups ";
  }
  const std::set<std::string> before = listing(dir);
  const CommandResult r = run_twinray(substitute(render("{dir}/s.json"), dir), prefix);
  expect_clean_failure(r, {"s.json", "ermission denied"}, before, dir);
  std::filesystem::remove_all(dir);
}

// When the EXR is written and then the PNG or the JSON summary cannot be, the EXR must not stay behind
// (it would be a partial result of a failed command).
TEST(BadInputTablePaths, NoExrLeftWhenALaterOutputCannotBeWritten) {
  for (const char* later : {"--png {dir}/nofolder/out.png", "--json {dir}/f.txt/r.json"}) {
    const std::filesystem::path dir = write_files("later-output-fails", {{"s.json", scene(kSphere)}, {"f.txt", "x"}});
    const std::set<std::string> before = listing(dir);
    const CommandResult r =
        run_twinray(substitute(std::string("render {dir}/s.json --spp 1 -o {dir}/out.exr ") + later, dir));
    expect_clean_failure(r, {}, before, dir);
    std::filesystem::remove_all(dir);
  }
}

}  // namespace
}  // namespace twinray::testing
