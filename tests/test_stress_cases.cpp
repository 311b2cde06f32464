// The `twinray stress` catalogue at a small effort, in-process: every case must pass on the backends that
// claim to handle it (bvh, brute, embree), plus the helpers the cases rely on, plus the command's contract
// through the real binary.

#include "harness/stress/stress_case.h"
#include "harness/stress/stress_support.h"
#include "cli_runner.h"
#include "core/scene/procedural.h"
#include "core/util/fp_mode.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <map>
#include <set>
#include <string>
#include <utility>

namespace twinray::stress {
namespace {

// 5% of the command's default work: a few seconds for the whole catalogue on three backends.
constexpr double kTestEffort = 0.05;

// Findings of the catalogue that belong to other components, reported to their owners (see
// docs/stress.md, "Open findings"), listed here by name rather than skipped silently; the other backends
// still run these cases. Empty: lt-grazing on brute was fixed by scaling the spawn offset with the
// vertex magnitudes (core/geometry/ray_offset.h).
const std::set<std::pair<std::string, std::string>> kOpenFindings = {};

struct Param {
  std::string case_name, backend;
};
std::ostream& operator<<(std::ostream& os, const Param& p) { return os << p.case_name << "/" << p.backend; }

// Cases a backend is run on but not required to pass (the reason is the case's note): Embree computes t in
// float, beyond the arbiter's tolerance at 1e-4 degree grazing angles (docs/stress.md).
// And on extreme-scale, its float test over- and underflows at 2^-96 and 2^120.
const std::set<std::pair<std::string, std::string>> kReportedOnly = {{"grazing-slivers", "embree"},
                                                                     {"extreme-scale", "embree"}};

// Every case on bvh8, bvh, brute and embree; the exact backend on every case but the renders (which it skips).
std::vector<Param> params() {
  std::vector<Param> out;
  for (const StressCase& c : all_cases()) {
    for (const char* b : {"bvh8", "bvh", "brute", "embree"})
      if (!kOpenFindings.count({c.name, b})) out.push_back({c.name, b});
    if (c.family != "light-transport") out.push_back({c.name, "exact"});
  }
  return out;
}

class StressCatalogue : public ::testing::TestWithParam<Param> {};

TEST_P(StressCatalogue, PassesOnBackendsThatClaimIt) {
  const ScopedFlushDenormals ftz;
  const StressCase* c = find_case(GetParam().case_name);
  ASSERT_NE(c, nullptr);
  const Outcome o = c->run(GetParam().backend, StressOptions{kTestEffort});
  if (kReportedOnly.count({GetParam().case_name, GetParam().backend})) {
    EXPECT_FALSE(o.required) << o.figures;
    EXPECT_FALSE(o.counts_as_failure());
    return;
  }
  EXPECT_TRUE(o.required) << o.note;
  EXPECT_EQ(o.status, Status::Pass) << o.figures << "\n" << o.note << "\n" << o.json.dump(1);
}

// The exact backend is an arbiter for single rays: the light-transport renders skip it, and say so.
TEST(StressCatalogue, RendersSkipTheExactBackend) {
  const Outcome o = find_case("lt-furnace-long-paths")->run("exact", StressOptions{kTestEffort});
  EXPECT_EQ(o.status, Status::Skip);
  EXPECT_FALSE(o.counts_as_failure());
  EXPECT_NE(o.note.find("exact"), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(Catalogue, StressCatalogue, ::testing::ValuesIn(params()),
                         [](const ::testing::TestParamInfo<Param>& p) {
                           std::string s = p.param.case_name + "_" + p.param.backend;
                           for (char& ch : s)
                             if (ch == '-') ch = '_';
                           return s;
                         });

TEST(StressCatalogue, NamesAreUniqueAndCoverEveryFamily) {
  std::set<std::string> names, families;
  for (const StressCase& c : all_cases()) {
    EXPECT_TRUE(names.insert(c.name).second) << c.name;
    families.insert(c.family);
    EXPECT_FALSE(c.summary.empty()) << c.name;
  }
  EXPECT_EQ(families, (std::set<std::string>{"geometry", "robustness", "scale", "light-transport"}));
  EXPECT_EQ(find_case("no-such-case"), nullptr);
}

// embree-fast is never required, whatever happens.
TEST(StressCatalogue, FastModeIsReportedNotRequired) {
  const ScopedFlushDenormals ftz;
  const Outcome o = find_case("closed-mesh-inside")->run("embree-fast", StressOptions{kTestEffort});
  EXPECT_FALSE(o.required);
  EXPECT_FALSE(o.counts_as_failure());
}

// The integer box is closed: every directed edge appears once and its reverse once (positions compared,
// since faces do not share vertex indices), and every face winds outward.
TEST(StressSupport, IntegerBoxIsClosedAndOutward) {
  const TriangleMesh box = integer_box_mesh(-1, 2);
  EXPECT_EQ(box.indices.size(), 6u * 3u * 3u * 2u);
  std::map<std::pair<std::array<float, 3>, std::array<float, 3>>, int> edges;
  auto key = [](const glm::vec3& v) { return std::array<float, 3>{v.x, v.y, v.z}; };
  for (const glm::uvec3& t : box.indices) {
    for (int k = 0; k < 3; ++k) ++edges[{key(box.positions[t[k]]), key(box.positions[t[(k + 1) % 3]])}];
    const glm::vec3 a = box.positions[t[0]], b = box.positions[t[1]], c = box.positions[t[2]];
    const glm::vec3 n = glm::cross(b - a, c - a);
    const glm::vec3 centroid = (a + b + c) / 3.0f - glm::vec3(0.5f);  // box centre is 0.5
    EXPECT_GT(glm::dot(n, centroid), 0.0f);
  }
  for (const auto& [e, count] : edges) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(edges.count({e.second, e.first}), 1u);
  }
  EXPECT_GT(box.positions.capacity(), box.positions.size());
}

TEST(StressSupport, CountCrossingsCountsEntryAndExit) {
  SceneGeometry g;
  g.meshes.push_back(integer_box_mesh(0, 4));
  const auto backend = build_backend("bvh", g);
  Ray through;
  through.org = {2.5f, 1.5f, 10.0f};
  through.dir = {0.0f, 0.0f, -1.0f};
  EXPECT_EQ(count_crossings(*backend, through), 2);
  Ray past = through;
  past.org.x = 5.0f;
  EXPECT_EQ(count_crossings(*backend, past), 0);
  Ray stops_inside = through;
  stops_inside.tmax = 8.0f;  // enters at t = 6, exits at t = 10
  EXPECT_EQ(count_crossings(*backend, stops_inside), 1);
}

TEST(StressSupport, RequirementFollowsClaims) {
  Outcome a;
  set_requirement(a, "bvh", true, "x");
  EXPECT_TRUE(a.required);
  Outcome b;
  set_requirement(b, "embree-fast", true, "x");
  EXPECT_FALSE(b.required);
  Outcome c;
  set_requirement(c, "plugin:foo", false, "watertightness");
  EXPECT_FALSE(c.required);
  EXPECT_NE(c.note.find("watertightness"), std::string::npos);
}

}  // namespace
}  // namespace twinray::stress

namespace twinray::testing {
namespace {

TEST(StressCommand, ListsEveryCase) {
  const CommandResult r = run_twinray("stress --list");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  for (const stress::StressCase& c : stress::all_cases()) EXPECT_NE(r.output.find(c.name), std::string::npos) << c.name;
}

TEST(StressCommand, RunsSelectedCasesAndWritesJson) {
  const auto dir = scratch_dir("stress-json");
  const CommandResult r = run_twinray("stress --case invalid-rays --case nonfinite-vertices --backends bvh,embree-fast "
                                      "--effort 0.05 --json " + quoted(dir / "s.json"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("verdict: PASS"), std::string::npos) << r.output;
  std::ifstream in(dir / "s.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("verdict"), "pass");
  ASSERT_EQ(j.at("results").size(), 4u);
  for (const auto& res : j.at("results")) {
    for (const char* key : {"case", "family", "backend", "status", "required", "seconds", "figures", "details"})
      EXPECT_TRUE(res.contains(key)) << key;
    EXPECT_EQ(res.at("required"), res.at("backend") != "embree-fast");
  }
}

// A backend that loses triangles must make a required case fail, with exit code 1.
TEST(StressCommand, ExitsOneWhenAClaimingBackendFails) {
  const CommandResult r = run_twinray(std::string("stress --case nonfinite-vertices --effort 0.05 --backends plugin:") +
                                      TWINRAY_TEST_BUGGY_PLUGIN);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("FAIL"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace twinray::testing
