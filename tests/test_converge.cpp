// twinray converge: the error metrics and slope fit exactly, and the command end to end on a tiny scene.

#include "harness/converge/error_metrics.h"
#include "harness/converge/reference_cache.h"
#include "harness/converge/slope_fit.h"
#include "cli_runner.h"
#include "core/scene/scene_loader.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <vector>

namespace twinray {
namespace {

using testing::quoted;
using testing::run_twinray;
using testing::scratch_dir;
using testing::source_path;

TEST(ConvergeSlopeFit, OneOverNSeriesHasSlopeMinusOne) {
  std::vector<double> n, error;
  for (double x = 1.0; x <= 4096.0; x *= 2.0) {
    n.push_back(x);
    error.push_back(0.37 / x);
  }
  const converge::PowerLawFit fit = converge::fit_power_law(n, error);
  ASSERT_TRUE(fit.valid());
  EXPECT_EQ(fit.points, 13);
  EXPECT_NEAR(fit.slope, -1.0, 1e-12);
  EXPECT_NEAR(std::exp(fit.intercept), 0.37, 1e-12);
  EXPECT_NEAR(fit.r_squared, 1.0, 1e-12);
}

TEST(ConvergeSlopeFit, SkipsNonPositivePointsAndNeedsTwo) {
  const std::vector<double> x = {0.0, 1.0, 4.0, -2.0}, y = {5.0, 2.0, 1.0, 3.0};
  const converge::PowerLawFit fit = converge::fit_power_law(x, y);
  EXPECT_EQ(fit.points, 2);
  EXPECT_NEAR(fit.slope, -0.5, 1e-12);  // (1, 2) and (4, 1): log 0.5 / log 4
  const std::vector<double> one = {3.0};
  EXPECT_FALSE(converge::fit_power_law(one, one).valid());
}

TEST(ConvergeErrorMetrics, MatchHandComputedValues) {
  Image ref(2, 1, 3), img(2, 1, 3);
  // Pixel 0: reference 1, error +0.5 in every channel; pixel 1: reference 0, error -0.1.
  for (int c = 0; c < 3; ++c) {
    ref.at(0, 0, c) = 1.0f;
    img.at(0, 0, c) = 1.5f;
    ref.at(1, 0, c) = 0.0f;
    img.at(1, 0, c) = -0.1f;
  }
  const converge::ErrorMetrics e = converge::compute_error(img, ref);
  const double rel = (0.25 / (1.0 + converge::kRelMseEpsilon) + 0.01 / converge::kRelMseEpsilon) / 2.0;
  EXPECT_NEAR(e.rel_mse, rel, 1e-7);
  EXPECT_NEAR(e.rmse, std::sqrt((0.25 + 0.01) / 2.0), 1e-7);
  EXPECT_NEAR(e.mae, (0.5 + 0.1) / 2.0, 1e-7);
  EXPECT_THROW(converge::compute_error(Image(3, 1, 3), ref), std::invalid_argument);
}

TEST(ConvergeReferenceCache, KeyChangesWithSceneAndSettings) {
  const Scene scene = load_scene(source_path("scenes/cornell-box.json"));
  converge::ReferenceSettings rs;
  const std::uint64_t key = converge::reference_key(scene, rs);
  EXPECT_EQ(key, converge::reference_key(scene, rs));  // deterministic
  converge::ReferenceSettings more = rs;
  more.spp *= 2;
  EXPECT_NE(key, converge::reference_key(scene, more));
  Scene moved = scene;
  moved.geometry.meshes[0].positions[0].x += 1e-3f;
  EXPECT_NE(key, converge::reference_key(moved, rs));
}

// The Cornell box at 24x24 pixels: the whole study (reference at 32 spp, points at 1..4 spp) takes well
// under a second.
std::filesystem::path tiny_cornell_box(const std::filesystem::path& dir) {
  std::ifstream in(source_path("scenes/cornell-box.json"));
  nlohmann::json j;
  in >> j;
  j["camera"]["width"] = 24;
  j["camera"]["height"] = 24;
  const std::filesystem::path path = dir / "tiny-cornell.json";
  std::ofstream(path) << j.dump();
  return path;
}

TEST(ConvergeCommand, WritesCsvJsonPlotAndImagesWithDocumentedKeys) {
  const std::filesystem::path dir = scratch_dir("converge");
  setenv("TWINRAY_CACHE_DIR", (dir / "cache").c_str(), 1);
  const std::filesystem::path scene = tiny_cornell_box(dir);
  const std::filesystem::path out = dir / "out";
  const auto r = run_twinray("converge " + quoted(scene) + " --backends bvh,embree --strategies mis,light " +
                             "--reference-spp 32 --budget 30 --threads 1 --out " + quoted(out));
  ASSERT_EQ(r.exit_code, 0) << r.output;

  // --reference-spp 32 caps the study at 32 / 8 = 4 spp: points 1, 2, 4 (the budget is far from used).
  std::ifstream json_in(out / "converge.json");
  const nlohmann::json j = nlohmann::json::parse(json_in);
  for (const char* key : {"scene", "reference", "backends", "strategies", "budget_seconds", "max_spp", "seed",
                          "threads", "error_metric_epsilon", "series", "plot", "csv"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["max_spp"], 4);
  EXPECT_TRUE(j["reference"]["cached"].get<bool>());
  EXPECT_TRUE(std::filesystem::exists(j["reference"]["path"].get<std::string>()));
  ASSERT_EQ(j["series"].size(), 4u);  // 2 backends x 2 strategies
  for (const auto& s : j["series"]) {
    ASSERT_EQ(s["points"].size(), 3u) << s.dump();
    EXPECT_EQ(s["points"][2]["spp"], 4);
    for (const char* key : {"spp", "seconds", "rel_mse", "rmse", "mae"}) EXPECT_TRUE(s["points"][0].contains(key)) << key;
    // More samples, less error: at 4x the samples relMSE must have dropped (expected factor 4).
    EXPECT_LT(s["points"][2]["rel_mse"].get<double>(), s["points"][0]["rel_mse"].get<double>());
    EXPECT_TRUE(s["slope"].is_number());
    for (const auto& [key, rel] : s["images"].items()) EXPECT_TRUE(std::filesystem::exists(out / rel.get<std::string>())) << key;
  }
  // bvh and embree hit the same primitives with the same random numbers; only the last bits of t and the
  // barycentrics differ (different arithmetic), which moves bounce origins by ulps: errors agree to 1e-3.
  const double bvh_error = j["series"][0]["points"][2]["rel_mse"].get<double>();
  const double embree_error = j["series"][2]["points"][2]["rel_mse"].get<double>();
  EXPECT_NEAR(bvh_error, embree_error, 1e-3 * embree_error);

  std::ifstream csv_in(out / "converge.csv");
  std::string header;
  std::getline(csv_in, header);
  EXPECT_EQ(header, "backend,strategy,spp,seconds,rel_mse,rmse,mae");
  int rows = 0;
  for (std::string line; std::getline(csv_in, line);) ++rows;
  EXPECT_EQ(rows, 12);
  ASSERT_TRUE(j["plot"].is_string()) << "gnuplot missing: run scripts/install-deps.sh";
  EXPECT_TRUE(std::filesystem::exists(out / j["plot"].get<std::string>()));

  // A second run finds the cached reference.
  const auto again = run_twinray("converge " + quoted(scene) + " --backends bvh --strategies mis --reference-spp 32 " +
                                 "--budget 30 --threads 1 --out " + quoted(dir / "out2"));
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("(cached)"), std::string::npos) << again.output;
  unsetenv("TWINRAY_CACHE_DIR");
}

TEST(ConvergeCommand, BadInputExitsWithTwo) {
  const std::filesystem::path dir = scratch_dir("converge-bad");
  const std::filesystem::path scene = tiny_cornell_box(dir);
  EXPECT_EQ(run_twinray("converge " + quoted(scene) + " --strategies nope").exit_code, 2);
  EXPECT_EQ(run_twinray("converge " + quoted(scene) + " --backends nope").exit_code, 2);
  EXPECT_EQ(run_twinray("converge " + quoted(scene) + " --budget 0").exit_code, 2);
  // The Cornell box has no environment map to compare sampling strategies on.
  EXPECT_EQ(run_twinray("converge " + quoted(scene) + " --strategies env-uniform").exit_code, 2);
  EXPECT_EQ(run_twinray("converge " + quoted(scene) + " --reference " + quoted(dir / "missing.exr")).exit_code, 2);
}

}  // namespace
}  // namespace twinray
