#include "harness/converge/peer_series.h"

#include "harness/compare/mitsuba_peer.h"
#include "core/scene/mitsuba_export.h"

#include <fmt/core.h>

namespace twinray::converge {

ConvergeSeries mitsuba_series(const Scene& scene, const Image& reference, const StudySettings& settings,
                              const std::filesystem::path& work_dir, int threads,
                              const std::function<void(const std::string&)>& log) {
  const compare::MitsubaInstall install = compare::find_mitsuba();
  Scene exported = scene;
  exported.render.max_depth = settings.max_depth;
  MitsubaExportOptions options;
  options.rr_depth = settings.rr_depth;
  const std::filesystem::path xml = export_mitsuba_scene(exported, work_dir, options);
  const compare::MitsubaSweep sweep = compare::sweep_with_mitsuba(install, xml, work_dir / "sweep", settings.budget_seconds,
                                                                  settings.max_spp, settings.seed, threads);
  ConvergeSeries series;
  series.backend = "mitsuba";
  series.strategy = sweep.variant;
  std::vector<double> t, n, e;
  for (const compare::MitsubaSweepPoint& p : sweep.points) {
    ConvergePoint point;
    point.spp = p.spp;
    point.seconds = p.seconds;
    point.error = compute_error(p.image, reference);
    series.points.push_back(point);
    series.last_image = p.image;
    t.push_back(point.seconds);
    n.push_back(point.spp);
    e.push_back(point.error.rel_mse);
    log(fmt::format("{:>12} {:>14} {:>7} spp {:>9.3f} s  relMSE {:.4e}  RMSE {:.4e}  MAE {:.4e}", "mitsuba", sweep.variant,
                    point.spp, point.seconds, point.error.rel_mse, point.error.rmse, point.error.mae));
  }
  series.rel_mse_fit = fit_power_law(t, e);
  series.rel_mse_spp_fit = fit_power_law(n, e);
  return series;
}

}  // namespace twinray::converge
