// twinray report: parsing of benchmark JSON, scaling checks, cost heatmaps, and the command end to end on
// a small benchmark fixture (HTML and Markdown referencing image files that exist).

#include "backends/registry.h"
#include "harness/report/bench_results.h"
#include "harness/report/cost_heatmap.h"
#include "harness/report/scaling.h"
#include "cli_runner.h"
#include "core/scene/procedural_bench.h"
#include "core/util/input_error.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>

namespace twinray {
namespace {

using testing::quoted;
using testing::run_twinray;
using testing::scratch_dir;

nlohmann::json build_row(const std::string& scene, const std::string& backend, const std::string& family, double n,
                         double ms, double speed) {
  return {{"name", "build/" + scene + "/" + backend + "/manual_time"},
          {"run_name", "build/" + scene + "/" + backend + "/manual_time"},
          {"run_type", "iteration"},
          {"label", family},
          {"triangles", n},
          {"build_ms", ms},
          {"Mprims_per_s", n / ms * 1e-3},
          {"speed_vs_embree_fast", speed},
          {"memory_bytes", 64.0 * n},
          {"bytes_per_prim", 64.0},
          {"nodes", backend == "bvh" ? n : 0.0},
          {"depth", backend == "bvh" ? std::log2(n) : 0.0}};
}

nlohmann::json trace_row(const std::string& scene, const std::string& backend, const std::string& family, double n,
                         const std::string& kind, const std::string& query, double mrays, double speed) {
  const std::string name = "trace/" + scene + "/" + backend + "/" + kind + "/" + query + "/threads:1/real_time";
  nlohmann::json j = {{"name", name},  {"run_name", name}, {"run_type", "iteration"}, {"label", family},
                      {"triangles", n}, {"Mrays_per_s", mrays}, {"speed_vs_embree_fast", speed}, {"hit_fraction", 0.5}};
  if (backend == "bvh") {
    j["nodes_per_ray"] = 4.0 * std::log2(n);
    j["nodes_per_ray_p99"] = 10.0 * std::log2(n);
    j["prims_per_ray"] = 3.0;
    j["prims_per_ray_p99"] = 8.0;
  }
  return j;
}

// Two scale-series sizes, one mesh, bvh at half embree-fast's speed everywhere.
nlohmann::json bench_fixture() {
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& [scene, family, n] : {std::tuple{"sphere-1k", "sphere", 1024.0}, std::tuple{"sphere-16k", "sphere", 16384.0},
                                         std::tuple{"bunny", "mesh", 69451.0}}) {
    rows.push_back(build_row(scene, "embree-fast", family, n, n * 1e-4, 1.0));
    rows.push_back(build_row(scene, "bvh", family, n, n * 2e-4, 0.5));
    for (const char* kind : {"primary", "shadow", "diffuse"})
      for (const char* query : {"closest", "any"}) {
        rows.push_back(trace_row(scene, "embree-fast", family, n, kind, query, 10.0, 1.0));
        rows.push_back(trace_row(scene, "bvh", family, n, kind, query, 5.0, 0.5));
      }
  }
  return {{"context", {{"date", "2026-01-01T00:00:00"}, {"host_name", "fixture"}, {"num_cpus", 2}}},
          {"benchmarks", rows}};
}

TEST(ReportBenchResults, ParsesNamesCountersAndPrefersMedians) {
  nlohmann::json j = bench_fixture();
  // A repeated benchmark: its median aggregate replaces the iteration rows.
  nlohmann::json median = j["benchmarks"][1];
  median["run_type"] = "aggregate";
  median["aggregate_name"] = "median";
  median["name"] = median["name"].get<std::string>() + "_median";
  median["build_ms"] = 123.0;
  j["benchmarks"].push_back(median);
  const report::BenchResults r = report::parse_bench_results(j, "fixture.json");
  EXPECT_EQ(r.builds.size(), 6u);
  EXPECT_EQ(r.traces.size(), 36u);
  const auto b = r.build("sphere-1k", "bvh");
  ASSERT_TRUE(b);
  EXPECT_EQ(b->build_ms, 123.0);
  EXPECT_EQ(b->family, "sphere");
  const auto t = r.trace("bunny", "bvh", "shadow", "any", 1);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->mrays_per_s, 5.0);
  EXPECT_TRUE(t->has_cost);
  EXPECT_FALSE(r.trace("bunny", "embree-fast", "shadow", "any", 1)->has_cost);
  EXPECT_EQ(r.context.at("host_name"), "fixture");
  EXPECT_THROW(report::parse_bench_results(nlohmann::json::object(), "x.json"), InputError);
}

TEST(ReportScaling, RecognisesModelsAndDepartures) {
  std::vector<double> n, nlogn, quadratic, logn, flat, growing;
  for (double x = 1024; x <= 4194304; x *= 4) {
    n.push_back(x);
    nlogn.push_back(3e-6 * x * std::log2(x));
    quadratic.push_back(1e-9 * x * x);
    logn.push_back(2.0 * std::log2(x));
    flat.push_back(64.0 + (x > 1e5 ? 4.0 : 0.0));
    growing.push_back(std::sqrt(x));
  }
  const report::ScalingCheck build = report::check_n_log_n("build time", "s", n, nlogn);
  EXPECT_NEAR(build.measured, build.expected, 1e-12);
  EXPECT_FALSE(build.departs);
  EXPECT_TRUE(report::check_n_log_n("build time", "s", n, quadratic).departs);
  EXPECT_FALSE(report::check_log_n("nodes", "s", n, logn).departs);
  EXPECT_TRUE(report::check_log_n("nodes", "s", n, growing).departs);
  EXPECT_FALSE(report::check_flat("bytes", "s", n, flat).departs);
  EXPECT_TRUE(report::check_flat("bytes", "s", n, growing).departs);
}

TEST(ReportCostHeatmap, BruteForceTestsEveryPrimitiveAtEveryPixel) {
  Scene scene = bench_scene(bench_sphere(200), "sphere", 16, 12);
  const std::size_t triangles = scene.geometry.triangle_count();
  auto brute = make_backend("brute");
  brute->build(scene.geometry);
  const report::CostImages cost = report::traversal_cost_images(scene, *brute);
  ASSERT_EQ(cost.primitives.width, 16);
  ASSERT_EQ(cost.primitives.height, 12);
  for (float v : cost.primitives.data) EXPECT_EQ(v, static_cast<float>(triangles));
  EXPECT_DOUBLE_EQ(cost.mean_primitives, static_cast<double>(triangles));
  auto embree = make_backend("embree");
  embree->build(scene.geometry);
  EXPECT_THROW(report::traversal_cost_images(scene, *embree), std::invalid_argument);
}

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(ReportCommand, WritesHtmlAndMarkdownReferencingExistingImages) {
  const std::filesystem::path dir = scratch_dir("report");
  std::ofstream(dir / "bench.json") << bench_fixture().dump(1);
  const std::filesystem::path out = dir / "out";
  const auto r = run_twinray("report --bench " + quoted(dir / "bench.json") + " --heatmap " +
                             quoted(testing::source_path("scenes/cornell-box.json")) + " --out " + quoted(out));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string html = read_text(out / "report.html");
  const std::string md = read_text(out / "report.md");
  ASSERT_FALSE(html.empty());
  ASSERT_FALSE(md.empty());

  int html_images = 0, md_images = 0;
  const std::regex img_src("<img src=\"([^\"]+)\"");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), img_src); it != std::sregex_iterator(); ++it, ++html_images)
    EXPECT_TRUE(std::filesystem::exists(out / (*it)[1].str())) << (*it)[1].str();
  const std::regex md_img(R"(!\[[^\]]*\]\(([^)]+)\))");
  for (auto it = std::sregex_iterator(md.begin(), md.end(), md_img); it != std::sregex_iterator(); ++it, ++md_images)
    EXPECT_TRUE(std::filesystem::exists(out / (*it)[1].str())) << (*it)[1].str();
  EXPECT_EQ(html_images, md_images);
  // Plots (throughput, five scaling plots) and the heatmap, when gnuplot is installed (install-deps.sh).
  EXPECT_GE(html_images, 7) << "gnuplot missing? run scripts/install-deps.sh";
  EXPECT_TRUE(std::filesystem::exists(out / "heatmaps" / "cornell-box.nodes.png"));

  // The headline row of bvh on the bunny: build 2e-4 * 69451 ms at 0.50x, 5 Mrays/s at 0.50x.
  EXPECT_NE(md.find("| bunny | 69451 | bvh | 13.9 | 0.50x | 5 | 0.50x | 5 | 0.50x | 5 | 0.50x |"), std::string::npos) << md;
  EXPECT_NE(html.find("<td class=\"num\">0.50x</td>"), std::string::npos);
}

TEST(ReportCommand, NothingToReportOrBadJsonExitsWithTwo) {
  const std::filesystem::path dir = scratch_dir("report-bad");
  EXPECT_EQ(run_twinray("report --out " + quoted(dir / "out")).exit_code, 2);
  std::ofstream(dir / "bad.json") << "{ not json";
  EXPECT_EQ(run_twinray("report --bench " + quoted(dir / "bad.json") + " --out " + quoted(dir / "out")).exit_code, 2);
  EXPECT_EQ(run_twinray("report --converge " + quoted(dir / "nowhere") + " --out " + quoted(dir / "out")).exit_code, 2);
}

}  // namespace
}  // namespace twinray
