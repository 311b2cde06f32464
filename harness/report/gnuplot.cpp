#include "harness/report/gnuplot.h"

#include "core/util/atomic_file.h"
#include "core/util/input_error.h"

#include <fmt/core.h>

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace twinray::report {

namespace {

std::string gnuplot_program() {
  const char* env = std::getenv("TWINRAY_GNUPLOT");
  return env && *env ? env : "gnuplot";
}

// A gnuplot double-quoted string literal.
std::string gp_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

// A POSIX shell single-quoted word.
std::string shell_quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') out += "'\\''";
    else out += c;
  }
  return out + "'";
}

// Colour-blind-safe qualitative palette (Okabe-Ito), then a few extra distinct colours.
const char* colour(std::size_t i) {
  static const char* palette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9",
                                  "#000000", "#F0E442", "#7F7F7F", "#8C564B", "#17BECF", "#BCBD22"};
  return palette[i % (sizeof(palette) / sizeof(palette[0]))];
}

std::string header(const std::string& title, int width, int height, const std::filesystem::path& svg) {
  std::string s;
  s += fmt::format("set terminal svg size {},{} dynamic enhanced font 'sans,12' background rgb 'white'\n", width, height);
  s += fmt::format("set output {}\n", gp_string(svg.string()));
  s += fmt::format("set title {} noenhanced\n", gp_string(title));
  s += "set grid xtics ytics mxtics mytics lc rgb '#dddddd'\n";
  s += "set key outside right top vertical Left reverse noenhanced\n";
  return s;
}

void run_gnuplot(const std::string& script, const std::filesystem::path& svg) {
  std::filesystem::path gp = svg;
  gp.replace_extension(".gp");
  write_file_atomically(gp, script);
  std::filesystem::path log = svg;
  log += ".log";
  const std::string command = fmt::format("{} {} > {} 2>&1", gnuplot_program(), shell_quoted(gp.string()),
                                          shell_quoted(log.string()));
  const int status = std::system(command.c_str());
  if (status != 0 || !std::filesystem::exists(svg))
    throw InputError(svg, "", "gnuplot failed (is gnuplot-nox installed? see " + log.string() + ")");
  std::error_code ec;
  std::filesystem::remove(log, ec);
}

}  // namespace

bool gnuplot_available() {
  const std::string command = gnuplot_program() + " --version > /dev/null 2>&1";
  return std::system(command.c_str()) == 0;
}

std::string line_plot_script(const LinePlot& plot, const std::filesystem::path& svg) {
  std::string s = header(plot.title, plot.width, plot.height, svg);
  s += fmt::format("set xlabel {} noenhanced\nset ylabel {} noenhanced\n", gp_string(plot.xlabel), gp_string(plot.ylabel));
  if (plot.log_x) s += "set logscale x\nset format x '10^{%T}'\n";
  if (plot.log_y) s += "set logscale y\nset format y '10^{%T}'\n";
  std::vector<std::string> plots;
  for (std::size_t i = 0; i < plot.series.size(); ++i) {
    const PlotSeries& series = plot.series[i];
    s += fmt::format("$data{} << EOD\n", i);
    std::size_t kept = 0;
    for (std::size_t k = 0; k < series.x.size() && k < series.y.size(); ++k) {
      const double x = series.x[k], y = series.y[k];
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      if ((plot.log_x && x <= 0.0) || (plot.log_y && y <= 0.0)) continue;
      s += fmt::format("{:.9g} {:.9g}\n", x, y);
      ++kept;
    }
    s += "EOD\n";
    if (kept == 0) continue;
    const std::string style = series.points ? "linespoints pt 7 ps 0.6" : "lines";
    plots.push_back(fmt::format("$data{} using 1:2 with {} lw 2 dt {} lc rgb '{}' title {} noenhanced", i, style,
                                series.dashed ? 2 : 1, colour(i), gp_string(series.title)));
  }
  if (plots.empty()) {
    s += "set label 1 'no data' at graph 0.5, graph 0.5 center\nplot [0:1] [0:1] NaN notitle\n";
  } else {
    s += "plot ";
    for (std::size_t i = 0; i < plots.size(); ++i) s += (i ? ", \\\n     " : "") + plots[i];
    s += "\n";
  }
  return s;
}

std::string bar_chart_script(const BarChart& chart, const std::filesystem::path& svg) {
  std::string s = header(chart.title, chart.width, chart.height, svg);
  s += fmt::format("set ylabel {} noenhanced\n", gp_string(chart.ylabel));
  s += "set style data histogram\nset style histogram clustered gap 1\nset style fill solid 0.85 border -1\n";
  s += "set boxwidth 0.9\nset xtics rotate by -30 noenhanced\nset yrange [0:*]\n";
  if (chart.log_y) s += "set logscale y\nset yrange [*:*]\n";
  s += "$bars << EOD\n";
  for (std::size_t c = 0; c < chart.categories.size(); ++c) {
    std::string label = chart.categories[c];
    for (char& ch : label)
      if (ch == ' ' || ch == '"') ch = '_';
    s += gp_string(label);
    for (std::size_t k = 0; k < chart.values.size(); ++k) {
      const double v = c < chart.values[k].size() ? chart.values[k][c] : NAN;
      s += std::isfinite(v) ? fmt::format(" {:.9g}", v) : std::string(" NaN");
    }
    s += "\n";
  }
  s += "EOD\n";
  if (chart.categories.empty() || chart.values.empty()) {
    s += "set label 1 'no data' at graph 0.5, graph 0.5 center\nplot [0:1] [0:1] NaN notitle\n";
    return s;
  }
  s += "plot ";
  for (std::size_t k = 0; k < chart.values.size(); ++k) {
    const std::string title = k < chart.series_titles.size() ? chart.series_titles[k] : fmt::format("series {}", k);
    s += fmt::format("{}$bars using {}{} lc rgb '{}' title {}", k ? ", \\\n     " : "", k + 2,
                     k == 0 ? ":xtic(1)" : "", colour(k), gp_string(title));
  }
  s += "\n";
  return s;
}

void plot_lines(const LinePlot& plot, const std::filesystem::path& svg) { run_gnuplot(line_plot_script(plot, svg), svg); }
void plot_bars(const BarChart& chart, const std::filesystem::path& svg) { run_gnuplot(bar_chart_script(chart, svg), svg); }

}  // namespace twinray::report
