#pragma once
// What `twinray converge` writes into its output folder (documented in docs/cli.md):
//   converge.csv          one row per point: backend,strategy,spp,seconds,rel_mse,rmse,mae
//   converge.json         settings, reference, and every series with its points, fits and image paths
//   error_vs_time.svg     log-log relMSE against seconds, one line per backend+strategy, slope in the legend
//                         (error_vs_time.gp beside it: the gnuplot script)
//   images/reference.png  the reference (sRGB)
//   images/BACKEND-STRATEGY.{exr,png}        render of the series' last point
//   images/BACKEND-STRATEGY.diff.{exr,png}   |render - reference| (PNG scaled x4 so small errors show)
//   images/BACKEND-STRATEGY.error.png        false-colour per-pixel relative squared error, log scale
// Paths inside converge.json are relative to the output folder.

#include "harness/converge/convergence_study.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace twinray::converge {

struct StudyDescription {
  std::string scene;
  std::string reference;         // path of the reference image used
  bool reference_cached = false; // true when it came from (or went into) the cache
  int reference_spp = 0;         // 0 when given by --reference
  double reference_seconds = 0.0;
  std::size_t threads = 0;
  StudySettings settings;
};

std::string series_label(const ConvergeSeries& s);  // "bvh mis"
std::string series_file_stem(const ConvergeSeries& s);  // "bvh-mis"

std::string converge_csv(const std::vector<ConvergeSeries>& series);
nlohmann::json converge_json(const StudyDescription& study, const std::vector<ConvergeSeries>& series,
                             bool plot_written);

// Writes every file listed above into `out` (created if needed). The plot is skipped (with plot_written =
// false in the JSON) when gnuplot is not available; returns whether it was written.
bool write_study_outputs(const std::filesystem::path& out, const StudyDescription& study,
                         const std::vector<ConvergeSeries>& series, const Image& reference);

}  // namespace twinray::converge
