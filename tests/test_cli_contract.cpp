// The command-line contract: exit codes, JSON keys and clean failure on bad input (docs/cli.md).

#include "tests/cli_runner.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace twinray::testing {
namespace {

nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

TEST(CliContract, HelpListsSubcommands) {
  const CommandResult r = run_twinray("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* sub : {"info", "crosscheck", "render"}) EXPECT_NE(r.output.find(sub), std::string::npos) << sub;
}

TEST(CliContract, InfoReportsFeaturesLeftOut) {
  const auto dir = scratch_dir("info");
  const CommandResult r =
      run_twinray("info " + quoted(source_path("scenes/cornell-box.json")) + " --json " + quoted(dir / "info.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = read_json(dir / "info.json");
  EXPECT_GT(j.at("triangles").get<int>(), 0);
  EXPECT_EQ(j.at("spheres").get<int>(), 0);
  bool saw_sphere_feature = false;
  for (const auto& f : j.at("features")) {
    if (f.at("name") == "sphere geometry") {
      saw_sphere_feature = true;
      EXPECT_FALSE(f.at("built").get<bool>());
    }
  }
  EXPECT_TRUE(saw_sphere_feature);
  EXPECT_NE(r.output.find("left out"), std::string::npos);
}

TEST(CliContract, RenderCausticsFlagAndJsonKeys) {
  const auto dir = scratch_dir("render-caustics");
  const std::string scene = quoted(source_path("scenes/cornell-mirror-glass.json"));
  for (const char* mode : {"auto", "off"}) {
    const auto json = dir / (std::string(mode) + ".json");
    const CommandResult r = run_twinray("render " + scene + " --spp 1 --caustics " + mode + " -o " +
                                        quoted(dir / (std::string(mode) + ".exr")) + " --json " + quoted(json));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json j = read_json(json);
    const bool on = std::string(mode) == "auto";
    EXPECT_EQ(j.at("caustics"), mode);
    EXPECT_EQ(j.at("caustic_light_tracing").get<bool>(), on);
    EXPECT_EQ(j.at("light_paths").get<std::uint64_t>(), on ? 256u * 256u : 0u);  // one per camera sample
    EXPECT_EQ(j.at("splats").get<std::uint64_t>() > 0, on);
    EXPECT_EQ(j.at("nonfinite_splats").get<std::uint64_t>(), 0u);
    EXPECT_EQ(r.output.find("caustics     ") != std::string::npos, on) << r.output;
  }
  const CommandResult bad = run_twinray("render " + scene + " --spp 1 --caustics maybe -o " + quoted(dir / "bad.exr"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("--caustics"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.exr"));
}

TEST(CliContract, RenderSplitsFlagAndJsonKey) {
  const auto dir = scratch_dir("render-splits");
  const std::string scene = quoted(source_path("scenes/cornell-box.json"));
  const CommandResult r = run_twinray("render " + scene + " --spp 1 --splits 2 -o " + quoted(dir / "s.exr") +
                                      " --json " + quoted(dir / "s.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_json(dir / "s.json").at("splits").get<int>(), 2);
  EXPECT_NE(r.output.find("splits 2"), std::string::npos) << r.output;
  for (const char* bad : {"0", "17"}) {
    const CommandResult b = run_twinray("render " + scene + " --spp 1 --splits " + bad + " -o " + quoted(dir / "bad.exr"));
    EXPECT_EQ(b.exit_code, 2) << bad;
    EXPECT_NE(b.output.find("--splits"), std::string::npos) << b.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.exr"));
  }
}

TEST(CliContract, RenderLightConnectionsFlagAndJsonKey) {
  const auto dir = scratch_dir("render-light-connections");
  const std::string scene = quoted(source_path("scenes/cornell-box.json"));
  const CommandResult r = run_twinray("render " + scene + " --spp 1 --light-connections 2 -o " + quoted(dir / "c.exr") +
                                      " --json " + quoted(dir / "c.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_json(dir / "c.json").at("light_connections").get<int>(), 2);
  EXPECT_NE(r.output.find("light connections 2"), std::string::npos) << r.output;
  const CommandResult b = run_twinray("render " + scene + " --spp 1 --light-connections 5 -o " + quoted(dir / "bad.exr"));
  EXPECT_EQ(b.exit_code, 2);
  EXPECT_NE(b.output.find("--light-connections"), std::string::npos) << b.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.exr"));
}

TEST(CliContract, InfoBuildsBackendsOnlyForGeometryPresent) {
  const auto dir = scratch_dir("info-build");
  const CommandResult r = run_twinray("info " + quoted(source_path("scenes/cornell-box.json")) +
                                      " --build bvh,embree --json " + quoted(dir / "info.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = read_json(dir / "info.json");
  for (const char* b : {"bvh", "embree"}) {
    EXPECT_TRUE(j.at("backends").at(b).at("built_triangles").get<bool>()) << b;
    EXPECT_FALSE(j.at("backends").at(b).at("built_spheres").get<bool>()) << b;
  }
  EXPECT_GT(j.at("backends").at("bvh").at("nodes").get<int>(), 0);
}

TEST(CliContract, CrosscheckPassesOnBundledScenesWithJsonKeys) {
  const auto dir = scratch_dir("crosscheck");
  for (const char* scene : {"scenes/cornell-box.json", "scenes/spheres.json"}) {
    const auto json = dir / "cc.json";
    const CommandResult r = run_twinray("crosscheck " + quoted(source_path(scene)) +
                                        " --backends bvh,embree,brute --rays 3000 --json " + quoted(json));
    ASSERT_EQ(r.exit_code, 0) << scene << "\n" << r.output;
    const nlohmann::json j = read_json(json);
    EXPECT_EQ(j.at("genuine_mismatches").get<int>(), 0);
    const double identical = j.at("identical_fraction").get<double>();
    EXPECT_GE(identical, 0.99) << scene;  // axis rays run through vertices on purpose: many edge cases there
    EXPECT_LE(identical, 1.0);
    EXPECT_EQ(j.at("verdict"), "pass");
    for (const char* kind : {"camera", "uniform", "diffuse", "shadow", "axis"}) {
      const auto& k = j.at("kinds").at(kind);
      EXPECT_GT(k.at("rays").get<int>(), 0) << kind;
      EXPECT_EQ(k.at("comparisons").size(), 2u);
      if (std::string(kind) == "axis") continue;
      for (const auto& c : k.at("comparisons"))
        EXPECT_GE(c.at("identical_fraction").get<double>(), 0.999) << scene << " " << kind;
    }
    // bvh and brute share the intersection routines and the tie rule: they must agree exactly.
    for (const auto& [kind, k] : j.at("kinds").items()) {
      for (const auto& c : k.at("comparisons")) {
        if (c.at("backend") == "brute") {
          EXPECT_EQ(c.at("identical"), c.at("rays")) << scene << " " << kind;
        }
      }
    }
  }
}

// Every disagreement is ruled against the exact backend: per backend ruled / wrong / max_t_rel_error, the
// reasons and the first wrong answers; bvh and exact are never wrong.
TEST(CliContract, CrosscheckRulesDisagreementsWithTheArbiter) {
  const auto dir = scratch_dir("crosscheck-arbiter");
  const auto json = dir / "cc.json";
  const CommandResult r = run_twinray("crosscheck " + quoted(source_path("scenes/cornell-box.json")) +
                                      " --backends bvh,embree-fast,exact --rays 2000 --json " + quoted(json));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("arbiter (exact)"), std::string::npos) << r.output;
  const nlohmann::json j = read_json(json);
  ASSERT_TRUE(j.contains("arbiter"));
  for (const char* name : {"bvh", "embree-fast", "exact"}) {
    const auto& a = j.at("arbiter").at(name);
    EXPECT_GE(a.at("ruled").get<int>(), a.at("wrong").get<int>()) << name;
    EXPECT_GE(a.at("max_t_rel_error").get<double>(), 0.0) << name;
    EXPECT_TRUE(a.at("reasons").is_object()) << name;
    EXPECT_TRUE(a.at("reasons").contains("t-off")) << name;
    EXPECT_TRUE(a.at("wrong_examples").is_array()) << name;
    for (const auto& [kind, k] : j.at("kinds").items()) EXPECT_TRUE(k.at("arbiter").contains(name)) << kind;
  }
  EXPECT_EQ(j.at("arbiter").at("bvh").at("wrong"), 0);
  EXPECT_EQ(j.at("arbiter").at("exact").at("wrong"), 0);
  EXPECT_EQ(j.at("arbiter_settings").at("enabled"), true);
  EXPECT_EQ(j.at("arbiter_settings").at("max_rays_per_kind"), 100000);
  // bvh reports the exact t: it agrees with the exact backend on every ray of the bundled scene.
  for (const auto& [kind, k] : j.at("kinds").items())
    for (const auto& c : k.at("comparisons"))
      if (c.at("backend") == "exact") {
        EXPECT_EQ(c.at("max_rel_t_diff"), 0.0) << kind;
      }

  const CommandResult off = run_twinray("crosscheck " + quoted(source_path("scenes/cornell-box.json")) +
                                        " --backends bvh,embree-fast --rays 500 --no-arbiter --json " + quoted(json));
  ASSERT_EQ(off.exit_code, 0) << off.output;
  const nlohmann::json j_off = read_json(json);
  EXPECT_FALSE(j_off.contains("arbiter"));
  EXPECT_EQ(j_off.at("arbiter_settings").at("enabled"), false);
}

TEST(CliContract, CrosscheckAcceptsBareMesh) {
  const auto dir = scratch_dir("bare-mesh");
  {
    std::ofstream obj(dir / "tet.obj");
    obj << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
  }
  const CommandResult r = run_twinray("crosscheck " + quoted(dir / "tet.obj") + " --backends bvh,brute --rays 2000");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("PASS"), std::string::npos);
}

struct BadInvocation {
  const char* name;
  std::string args;
  const char* expected_in_message;
};

TEST(CliContract, BadInputExitsTwoWithMessageAndNoOutput) {
  const auto dir = scratch_dir("bad-input");
  {
    std::ofstream bad(dir / "broken.json");
    bad << "{\n  \"camera\": {\n    \"position\": [0, 0, 1],,\n  }\n}\n";
  }
  const std::string cornell = quoted(source_path("scenes/cornell-box.json"));
  const std::string json_out = quoted(dir / "out.json");
  const std::vector<BadInvocation> cases = {
      {"missing scene", "crosscheck " + quoted(dir / "nope.json") + " --json " + json_out, "nope.json"},
      {"malformed json", "crosscheck " + quoted(dir / "broken.json") + " --json " + json_out, "broken.json:3"},
      {"directory as scene", "info " + quoted(dir) + " --json " + json_out, "twinray-test-bad-input"},
      {"unknown backend", "crosscheck " + cornell + " --backends bvh,optix --json " + json_out, "optix"},
      {"one backend", "crosscheck " + cornell + " --backends bvh --json " + json_out, "at least two"},
      {"unknown kind", "crosscheck " + cornell + " --kinds camera,laser --json " + json_out, "laser"},
      {"zero rays", "crosscheck " + cornell + " --rays 0 --json " + json_out, "--rays"},
      {"negative rays", "crosscheck " + cornell + " --rays -5 --json " + json_out, "rays"},
      {"negative arbiter cap", "crosscheck " + cornell + " --arbiter-max-rays -1 --json " + json_out, "--arbiter-max-rays"},
      {"unknown flag", "crosscheck " + cornell + " --frobnicate", "frobnicate"},
      {"missing plugin", "crosscheck " + cornell + " --backends bvh,plugin:/nonexistent/libx.so --json " + json_out,
       "libx.so"},
  };
  for (const BadInvocation& c : cases) {
    const CommandResult r = run_twinray(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.name << "\n" << r.output;
    EXPECT_NE(r.output.find(c.expected_in_message), std::string::npos) << c.name << "\n" << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "out.json")) << c.name;
  }
  // Nothing but the inputs is left in the folder (no temporary files either).
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1u);
}

TEST(CliContract, UnwritableJsonTargetFailsCleanly) {
  const auto dir = scratch_dir("unwritable");
  const CommandResult r = run_twinray("info " + quoted(source_path("scenes/cornell-box.json")) + " --json " +
                                      quoted(dir / "no-such-folder" / "x.json"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("x.json"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace twinray::testing

namespace twinray::testing {
namespace {

// A BVH that loses one triangle per mesh must be caught: genuine mismatches, exit code 1, verdict "fail".
TEST(CliContract, CrosscheckExitsOneOnGenuineMismatch) {
  const auto dir = scratch_dir("buggy-plugin");
  const CommandResult r = run_twinray("crosscheck " + quoted(source_path("scenes/cornell-box.json")) +
                                      " --backends brute,plugin:" + TWINRAY_TEST_BUGGY_PLUGIN +
                                      " --rays 5000 --json " + quoted(dir / "cc.json"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("genuine"), std::string::npos);
  std::ifstream in(dir / "cc.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_GT(j.at("genuine_mismatches").get<int>(), 0);
  EXPECT_EQ(j.at("verdict"), "fail");
  EXPECT_LT(j.at("identical_fraction").get<double>(), 1.0);
  // The arbiter says who is right: the plugin's lost triangles are missed hits; the oracle is never wrong.
  const std::string plugin = std::string("plugin:") + TWINRAY_TEST_BUGGY_PLUGIN;
  EXPECT_GT(j.at("arbiter").at(plugin).at("wrong").get<int>(), 0);
  EXPECT_GT(j.at("arbiter").at(plugin).at("reasons").at("missed-hit").get<int>(), 0);
  EXPECT_EQ(j.at("arbiter").at("brute").at("wrong").get<int>(), 0);
  ASSERT_FALSE(j.at("arbiter").at(plugin).at("wrong_examples").empty());
  const auto& example = j.at("arbiter").at(plugin).at("wrong_examples").at(0);
  EXPECT_EQ(example.at("reason"), "missed-hit");
  EXPECT_TRUE(example.at("answer").is_null());
  EXPECT_TRUE(example.at("exact").is_object());
  EXPECT_NE(example.at("ray").at("hex").get<std::string>().find("0x"), std::string::npos);
  EXPECT_NE(r.output.find("bits: org (0x"), std::string::npos) << r.output;
}

// Crosscheck's axis rays (zero direction components of both signs) catch a slab test that takes -0 for +0,
// which camera, uniform, diffuse and shadow rays never exercise; and --strict turns the arbiter's rulings into
// the verdict: a plugin that claims watertightness and loses boxes in the planes through vertices (0 * inf =
// NaN) only shows "edge" disagreements, which the arbiter rules wrong.
TEST(CliContract, CrosscheckAxisRaysAndStrictCatchSlabTestBugs) {
  const std::string plugin_dir = TWINRAY_TEST_PLUGIN_DIR;
  const std::string scene = quoted(source_path("scenes/cornell-box.json"));
  const CommandResult neg_zero = run_twinray("crosscheck " + scene + " --backends bvh,plugin:" + plugin_dir +
                                             "/libtwinray_scotty_neg_zero_sign_plugin.so --rays 3000 --kinds axis");
  EXPECT_EQ(neg_zero.exit_code, 1) << neg_zero.output;
  const CommandResult other_kinds =
      run_twinray("crosscheck " + scene + " --backends bvh,plugin:" + plugin_dir +
                  "/libtwinray_scotty_neg_zero_sign_plugin.so --rays 3000 --kinds camera,uniform,diffuse,shadow");
  EXPECT_EQ(other_kinds.exit_code, 0) << "the other kinds were expected to miss this bug:\n" << other_kinds.output;

  const std::string nan_slab = " --backends bvh,plugin:" + plugin_dir + "/libtwinray_scotty_nan_slab_plugin.so";
  const CommandResult lenient = run_twinray("crosscheck " + scene + nan_slab + " --rays 5000 --kinds axis");
  EXPECT_EQ(lenient.exit_code, 0) << lenient.output;
  EXPECT_NE(lenient.output.find("the arbiter ruled wrong (reported; --strict fails on them)"), std::string::npos)
      << lenient.output;
  const auto dir = scratch_dir("strict");
  const CommandResult strict =
      run_twinray("crosscheck " + scene + nan_slab + " --rays 5000 --kinds axis --strict --json " + quoted(dir / "cc.json"));
  EXPECT_EQ(strict.exit_code, 1) << strict.output;
  std::ifstream in(dir / "cc.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("strict"), true);
  EXPECT_EQ(j.at("verdict"), "fail");
  EXPECT_EQ(j.at("genuine_mismatches"), 0);
  EXPECT_TRUE(j.at("kinds").contains("axis"));
}

// Crosscheck takes procedural scene names, as trace and grade do.
TEST(CliContract, CrosscheckAcceptsProceduralScenes) {
  const CommandResult r = run_twinray("crosscheck procedural:soup:500:3 --backends bvh,bvh8 --rays 500");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("verdict: PASS"), std::string::npos) << r.output;
  const CommandResult bad = run_twinray("crosscheck procedural:nonsense --backends bvh,bvh8 --rays 500");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
}

// The correct build of the same plugin passes against the built-in oracle.
TEST(CliContract, CrosscheckAcceptsCorrectPlugin) {
  const CommandResult r = run_twinray("crosscheck " + quoted(source_path("scenes/spheres.json")) +
                                      " --backends brute,plugin:" + TWINRAY_TEST_BRUTE_PLUGIN + " --rays 3000");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST(CliContract, ExportWritesAMitsubaSceneThatLoadsBack) {
  const auto dir = scratch_dir("export");
  const CommandResult r = run_twinray("export " + quoted(source_path("scenes/cornell-mirror-glass.json")) +
                                      " --to mitsuba " + quoted(dir / "out") + " --spp 16");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "scene.xml"));
  const CommandResult info = run_twinray("info " + quoted(dir / "out" / "scene.xml"));
  EXPECT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("spp 16"), std::string::npos) << info.output;
  const CommandResult bad = run_twinray("export " + quoted(source_path("scenes/cornell-box.json")) + " --to pbrt " +
                                        quoted(dir / "other"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("unknown format 'pbrt'"), std::string::npos) << bad.output;
}

TEST(CliContract, CompareWithoutMitsubaSaysWhichScriptInstallsIt) {
  const auto dir = scratch_dir("compare-missing");
  for (const std::string& command : {std::string("compare ") + quoted(source_path("scenes/cornell-box.json")) + " --spp 8 --out " + quoted(dir / "c"),
                                     std::string("converge ") + quoted(source_path("scenes/cornell-box.json")) + " --peer mitsuba --budget 1 --out " + quoted(dir / "v")}) {
    const CommandResult r = run_twinray(command, "TWINRAY_MITSUBA_VENV=" + (dir / "no-venv").string() + " ");
    EXPECT_EQ(r.exit_code, 2) << command;
    EXPECT_NE(r.output.find("scripts/setup-mitsuba.sh"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "c")) << "no output on bad input";
  }
}

}  // namespace
}  // namespace twinray::testing
