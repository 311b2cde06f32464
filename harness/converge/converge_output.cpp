#include "harness/converge/converge_output.h"

#include "harness/report/false_colour.h"
#include "harness/report/gnuplot.h"
#include "core/image/image_io.h"
#include "core/util/atomic_file.h"

#include <fmt/core.h>

#include <cmath>

namespace twinray::converge {

namespace {

// Differences are mostly a few percent of the image's range: scaled up so the PNG shows where they are.
constexpr float kDifferencePngGain = 4.0f;

Image scaled(Image img, float gain) {
  for (float& v : img.data) v *= gain;
  return img;
}

nlohmann::json fit_json(const PowerLawFit& f) {
  if (!f.valid()) return nullptr;
  return {{"slope", f.slope}, {"intercept", f.intercept}, {"r_squared", f.r_squared}, {"points", f.points}};
}

}  // namespace

std::string series_label(const ConvergeSeries& s) { return s.backend + " " + s.strategy; }

std::string series_file_stem(const ConvergeSeries& s) {
  std::string stem = s.backend + "-" + s.strategy;
  for (char& c : stem)
    if (c == '/' || c == ':' || c == ' ') c = '_';
  return stem;
}

std::string converge_csv(const std::vector<ConvergeSeries>& series) {
  std::string csv = "backend,strategy,spp,seconds,rel_mse,rmse,mae\n";
  for (const ConvergeSeries& s : series)
    for (const ConvergePoint& p : s.points)
      csv += fmt::format("{},{},{},{:.6g},{:.6e},{:.6e},{:.6e}\n", s.backend, s.strategy, p.spp, p.seconds,
                         p.error.rel_mse, p.error.rmse, p.error.mae);
  return csv;
}

nlohmann::json converge_json(const StudyDescription& study, const std::vector<ConvergeSeries>& series,
                             bool plot_written) {
  nlohmann::json j_series = nlohmann::json::array();
  for (const ConvergeSeries& s : series) {
    nlohmann::json points = nlohmann::json::array();
    for (const ConvergePoint& p : s.points)
      points.push_back({{"spp", p.spp}, {"seconds", p.seconds}, {"rel_mse", p.error.rel_mse}, {"rmse", p.error.rmse},
                        {"mae", p.error.mae}});
    const std::string stem = "images/" + series_file_stem(s);
    j_series.push_back({
        {"backend", s.backend},
        {"strategy", s.strategy},
        {"build_seconds", s.build_seconds},
        {"points", points},
        {"slope", s.rel_mse_fit.valid() ? nlohmann::json(s.rel_mse_fit.slope) : nlohmann::json(nullptr)},
        {"fit_time", fit_json(s.rel_mse_fit)},
        {"fit_spp", fit_json(s.rel_mse_spp_fit)},
        {"images",
         {{"render_exr", stem + ".exr"},
          {"render_png", stem + ".png"},
          {"difference_exr", stem + ".diff.exr"},
          {"difference_png", stem + ".diff.png"},
          {"error_png", stem + ".error.png"}}},
    });
  }
  std::vector<std::string> strategies;
  for (const StrategySpec& s : study.settings.strategies) strategies.push_back(s.name);
  return {
      {"scene", study.scene},
      {"reference",
       {{"path", study.reference},
        {"cached", study.reference_cached},
        {"spp", study.reference_spp},
        {"seconds", study.reference_seconds},
        {"png", "images/reference.png"}}},
      {"backends", study.settings.backends},
      {"strategies", strategies},
      {"budget_seconds", study.settings.budget_seconds},
      {"max_spp", study.settings.max_spp},
      {"seed", study.settings.seed},
      {"threads", study.threads},
      {"error_metric_epsilon", kRelMseEpsilon},
      {"series", j_series},
      {"plot", plot_written ? nlohmann::json("error_vs_time.svg") : nlohmann::json(nullptr)},
      {"csv", "converge.csv"},
  };
}

bool write_study_outputs(const std::filesystem::path& out, const StudyDescription& study,
                         const std::vector<ConvergeSeries>& series, const Image& reference) {
  std::filesystem::create_directories(out / "images");
  write_png(out / "images" / "reference.png", reference);
  for (const ConvergeSeries& s : series) {
    if (s.last_image.empty()) continue;
    const std::filesystem::path stem = out / "images" / series_file_stem(s);
    write_exr(stem.string() + ".exr", s.last_image);
    write_png(stem.string() + ".png", s.last_image);
    const Image diff = absolute_difference_image(s.last_image, reference);
    write_exr(stem.string() + ".diff.exr", diff);
    write_png(stem.string() + ".diff.png", scaled(diff, kDifferencePngGain));
    // Fixed log range 1e-4 .. 1 of relative squared error, so images of different series compare.
    const Image rel = relative_squared_error_image(s.last_image, reference);
    write_png(stem.string() + ".error.png", report::false_colour(rel, {1e-4, 1.0, true}));
  }

  bool plot_written = false;
  if (report::gnuplot_available()) {
    report::LinePlot plot;
    plot.title = "relMSE against render time: " + std::filesystem::path(study.scene).filename().string();
    plot.xlabel = "wall time per image (s)";
    plot.ylabel = "relMSE";
    plot.log_x = plot.log_y = true;
    for (const ConvergeSeries& s : series) {
      report::PlotSeries ps;
      ps.title = s.rel_mse_fit.valid() ? fmt::format("{} (slope {:.2f})", series_label(s), s.rel_mse_fit.slope)
                                       : series_label(s);
      for (const ConvergePoint& p : s.points) {
        ps.x.push_back(p.seconds);
        ps.y.push_back(p.error.rel_mse);
      }
      plot.series.push_back(std::move(ps));
    }
    report::plot_lines(plot, out / "error_vs_time.svg");
    plot_written = true;
  }
  write_file_atomically(out / "converge.csv", converge_csv(series));
  write_file_atomically(out / "converge.json", converge_json(study, series, plot_written).dump(2) + "\n");
  return plot_written;
}

}  // namespace twinray::converge
