#pragma once
// `twinray report`: benchmark JSON + convergence folders + traversal-cost heatmaps -> report.html and
// its Markdown twin report.md, with plots (SVG, gnuplot) and images in the same folder, so the folder is
// self-contained and can be copied or served as is.

#include "harness/report/document.h"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace twinray::report {

struct ReportInputs {
  std::filesystem::path bench;                        // Google Benchmark JSON of twinray_bench (optional)
  std::vector<std::filesystem::path> converge_dirs;   // output folders of `twinray converge`
  std::vector<std::filesystem::path> heatmap_scenes;  // scenes for per-pixel bvh traversal cost
  std::filesystem::path out;
};

// Builds the document, writing plots and images into inputs.out as it goes. Throws InputError for
// unreadable inputs.
Document build_report(const ReportInputs& inputs, const std::function<void(const std::string&)>& log);

// build_report, then report.html and report.md into inputs.out. Returns the document.
Document write_report(const ReportInputs& inputs, const std::function<void(const std::string&)>& log);

}  // namespace twinray::report
