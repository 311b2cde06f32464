// Suite manifests (harness/grade/suite.h, docs/grading.md): the bundled suites load, and every mistake in a
// manifest is an InputError at the JSON pointer of the offending value.

#include "core/util/input_error.h"
#include "harness/grade/suite.h"
#include "tests/cli_runner.h"

#include <gtest/gtest.h>

#include <fstream>

namespace twinray::grade {
namespace {

std::filesystem::path write_manifest(const std::string& name, const std::string& text) {
  const std::filesystem::path dir = testing::scratch_dir("suite-" + name);
  std::ofstream(dir / kManifestName) << text;
  return dir;
}

// A valid manifest with `check` as its second check.
std::string manifest_with(const std::string& check) {
  return R"({"suite": "t", "scenes": {"s": "procedural:triangle", "c": "../c.json"},
             "checks": [{"name": "first", "category": "build", "scene": "s", "points": 1}, )" +
         check + "]}";
}

void expect_error_at(const std::string& check, const std::string& pointer, const std::string& words) {
  const auto dir = write_manifest("bad", manifest_with(check));
  try {
    parse_suite_manifest(dir / kManifestName);
    ADD_FAILURE() << "accepted: " << check;
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), pointer) << e.what();
    EXPECT_NE(e.message().find(words), std::string::npos) << e.what();
  }
}

TEST(GradeSuite, BundledSuitesLoadByName) {
  for (const char* name : {"default", "quick"}) {
    const Suite s = load_suite(name);
    EXPECT_EQ(s.name, name);
    EXPECT_TRUE(s.bundled);
    EXPECT_GT(s.checks.size(), 10u);
    // Every category of issue 10 is in both suites.
    for (Category c : kAllCategories) {
      bool found = false;
      for (const CheckSpec& check : s.checks) found = found || check.category == c;
      EXPECT_TRUE(found) << name << " lacks " << to_string(c);
    }
  }
  const std::vector<std::string> names = bundled_suite_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "quick"), names.end());
}

TEST(GradeSuite, ParsesEveryField) {
  const auto dir = write_manifest("fields", manifest_with(R"(
    {"name": "second", "category": "closest-hit", "scene": "c", "points": 2.5, "required": false,
     "visibility": "after_due_date", "time_limit": 7, "ray_time_limit": 0.5, "memory_limit_mib": 512, "seed": 9, "needs": ["first"],
     "rays": ["camera", "diffuse"], "count": 1000, "reference": "brute", "image": true, "description": "d"})"));
  const Suite s = parse_suite_manifest(dir / kManifestName);
  ASSERT_EQ(s.checks.size(), 2u);
  const CheckSpec& c = s.checks[1];
  EXPECT_EQ(c.category, Category::ClosestHit);
  EXPECT_EQ(c.points, 2.5);
  EXPECT_EQ(c.requirement, Requirement::Optional);
  EXPECT_EQ(c.visibility, Visibility::AfterDueDate);
  EXPECT_EQ(c.time_limit_seconds, 7.0);
  EXPECT_EQ(c.ray_time_limit_seconds, 0.5);
  EXPECT_EQ(s.checks[0].ray_time_limit_seconds, 2.0);  // the default
  EXPECT_EQ(c.memory_limit_bytes, std::size_t{512} << 20);
  EXPECT_EQ(c.seed, 9u);
  EXPECT_EQ(c.needs, std::vector<std::string>{"first"});
  EXPECT_EQ(c.rays.size(), 2u);
  EXPECT_EQ(c.count, 1000u);
  EXPECT_EQ(c.reference, Reference::Brute);
  EXPECT_TRUE(c.image);
  EXPECT_EQ(s.scenes.at("c").name, "../c.json");
  EXPECT_EQ(s.checks[0].requirement, Requirement::Required);  // the default
  EXPECT_EQ(s.checks[0].visibility, Visibility::Visible);
}

TEST(GradeSuite, TimeBudgetIsOptionalAndPositive) {
  EXPECT_FALSE(parse_suite_manifest(write_manifest("no-budget", manifest_with(R"({"name": "x", "category": "build",
    "scene": "s", "points": 1})")) / kManifestName).time_budget_seconds.has_value());
  const auto dir = write_manifest("budget", R"({"suite": "t", "time_budget": 90, "scenes": {"s": "procedural:triangle"},
      "checks": [{"name": "n", "category": "build", "scene": "s", "points": 1}]})");
  EXPECT_EQ(parse_suite_manifest(dir / kManifestName).time_budget_seconds, 90.0);
  const auto bad = write_manifest("bad-budget", R"({"suite": "t", "time_budget": 0, "scenes": {"s": "procedural:triangle"},
      "checks": [{"name": "n", "category": "build", "scene": "s", "points": 1}]})");
  try {
    parse_suite_manifest(bad / kManifestName);
    ADD_FAILURE() << "accepted a time budget of 0";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "/time_budget") << e.what();
  }
  // The bundled suites have one, generous for a correct plugin (docs/grading.md).
  for (const char* name : {"default", "quick"}) EXPECT_TRUE(load_suite(name).time_budget_seconds.has_value()) << name;
}

TEST(GradeSuite, SharedDataScenesAreMarked) {
  const auto dir = write_manifest("shared", R"({"suite": "t", "scenes": {
      "a": "$TWINRAY_SHARED/data/meshes/x.obj", "b": {"path": "x.json", "shared_data": true}, "c": "x.json"},
      "checks": [{"name": "n", "category": "build", "scene": "a", "points": 1}]})");
  const Suite s = parse_suite_manifest(dir / kManifestName);
  EXPECT_TRUE(s.scenes.at("a").needs_shared_data);
  EXPECT_TRUE(s.scenes.at("b").needs_shared_data);
  EXPECT_FALSE(s.scenes.at("c").needs_shared_data);
}

TEST(GradeSuite, MistakesAreReportedWhereTheyAre) {
  expect_error_at(R"({"name": "x", "category": "speed", "scene": "s", "points": 1})", "/checks/1/category", "unknown category");
  expect_error_at(R"({"name": "x", "category": "build", "scene": "nope", "points": 1})", "/checks/1/scene", "no scene 'nope'");
  expect_error_at(R"({"name": "first", "category": "build", "scene": "s", "points": 1})", "/checks/1/name", "two checks");
  expect_error_at(R"({"name": "Bad Name", "category": "build", "scene": "s", "points": 1})", "/checks/1/name", "a check name");
  expect_error_at(R"({"name": "x", "category": "build", "scene": "s", "points": -1})", "/checks/1/points", "points");
  expect_error_at(R"({"name": "x", "category": "build", "scene": "s"})", "/checks/1", "points");
  expect_error_at(R"({"name": "x", "category": "build", "scene": "s", "points": 1, "rays": "camera"})", "/checks/1/rays",
                  "unknown key 'rays' for a build check");
  expect_error_at(R"({"name": "x", "category": "closest-hit", "scene": "s", "points": 1, "rays": "laser"})",
                  "/checks/1/rays", "unknown ray kind");
  expect_error_at(R"({"name": "x", "category": "closest-hit", "scene": "s", "points": 1, "rays": "shadow"})",
                  "/checks/1/rays", "any-hit");
  expect_error_at(R"({"name": "x", "category": "closest-hit", "scene": "s", "points": 1, "rays": "uniform", "image": true})",
                  "/checks/1/image", "camera rays");
  expect_error_at(R"({"name": "x", "category": "build", "scene": "s", "points": 1, "needs": ["later"]})",
                  "/checks/1/needs/0", "not a check listed before");
  expect_error_at(R"({"name": "x", "category": "build", "scene": "s", "points": 1, "visibility": "public"})",
                  "/checks/1/visibility", "Gradescope");
  expect_error_at(R"({"name": "x", "category": "build", "scene": "s", "points": 1, "required": "if-claimed"})",
                  "/checks/1/required", "watertight and ties");
  expect_error_at(R"({"name": "x", "category": "build", "scene": "s", "points": 1, "time_limit": 0})",
                  "/checks/1/time_limit", "time limit");
  expect_error_at(R"({"name": "x", "category": "performance", "scene": "s", "points": 1, "thresholds": {"fast": 1}})",
                  "/checks/1/thresholds/fast", "unknown key");
  expect_error_at(R"({"name": "x", "category": "any-hit", "scene": "s", "points": 1, "reference": "oracle"})",
                  "/checks/1/reference", "brute");
}

TEST(GradeSuite, BadFilesAndNamesAreInputErrors) {
  EXPECT_THROW(load_suite("no-such-suite"), InputError);
  EXPECT_THROW(load_suite("/no/such/folder"), InputError);
  const auto dir = write_manifest("syntax", "{\"suite\": \"t\",");
  EXPECT_THROW(parse_suite_manifest(dir / kManifestName), InputError);
  const auto empty = write_manifest("empty-checks", R"({"suite": "t", "scenes": {}, "checks": []})");
  EXPECT_THROW(parse_suite_manifest(empty / kManifestName), InputError);
}

}  // namespace
}  // namespace twinray::grade
