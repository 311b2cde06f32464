#pragma once
// Plots as SVG files, drawn by gnuplot (Debian package gnuplot-nox, installed by scripts/install-deps.sh).
//
// Each plot is written as a self-contained gnuplot script (data in inline datablocks) beside the SVG,
// `NAME.gp`, and gnuplot is run on it: the script stays as the exact recipe of the figure, and anyone can
// re-run or restyle it. Titles are printed literally (no enhanced-text markup), so names like
// "embree-fast" or "sphere_64k" come out as written.

#include <filesystem>
#include <string>
#include <vector>

namespace twinray::report {

struct PlotSeries {
  std::string title;
  std::vector<double> x, y;  // same length; non-positive values are dropped on log axes
  bool dashed = false;       // fitted or reference lines
  bool points = true;        // draw markers
};

struct LinePlot {
  std::string title;
  std::string xlabel, ylabel;
  bool log_x = false, log_y = false;
  std::vector<PlotSeries> series;
  int width = 800, height = 520;
};

// Grouped bars: one group per category, one bar per series (values[series][category]).
struct BarChart {
  std::string title;
  std::string ylabel;
  std::vector<std::string> categories;
  std::vector<std::string> series_titles;
  std::vector<std::vector<double>> values;
  bool log_y = false;
  int width = 900, height = 520;
};

// The gnuplot program on PATH (or $TWINRAY_GNUPLOT) can be run.
bool gnuplot_available();

// Writes `svg` and the script `svg` with extension .gp. Throws InputError naming the file when gnuplot is
// missing or fails (its messages are in `svg`.log).
void plot_lines(const LinePlot& plot, const std::filesystem::path& svg);
void plot_bars(const BarChart& chart, const std::filesystem::path& svg);

// The script alone (for tests and for callers that only want the recipe).
std::string line_plot_script(const LinePlot& plot, const std::filesystem::path& svg);
std::string bar_chart_script(const BarChart& chart, const std::filesystem::path& svg);

}  // namespace twinray::report
