#include "harness/converge/convergence_study.h"

#include "backends/registry.h"
#include "core/render/renderer.h"
#include "core/util/fp_mode.h"

#include <fmt/core.h>

#include <chrono>
#include <sstream>
#include <stdexcept>

namespace twinray::converge {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Image render_with(const Scene& scene, const Backend& backend, const StrategySpec& strategy, int spp, int max_depth,
                  int rr_depth, std::uint64_t seed, double* seconds) {
  RenderOptions ro;
  ro.integrator = IntegratorKind::Path;
  ro.settings.max_depth = max_depth;
  ro.settings.rr_depth = rr_depth;
  ro.settings.strategy = strategy.strategy;
  ro.env_importance_sampling = strategy.env_importance;
  ro.spp = spp;
  ro.seed = seed;
  ro.show_progress = false;
  const ScopedFlushDenormals ftz;
  const auto start = std::chrono::steady_clock::now();
  // Setup counts toward the time: environment importance tables are part of that strategy's cost.
  const RenderSetup setup(scene, ro, backend.traits());
  const RenderResult result = render(setup, backend);
  if (seconds) *seconds = seconds_since(start);
  return result.film.mean_image();
}

}  // namespace

std::vector<StrategySpec> parse_strategies(const std::string& list) {
  std::vector<StrategySpec> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.empty()) continue;
    if (item == "mis") out.push_back({item, SamplingStrategy::Mis, true, false});
    else if (item == "bsdf") out.push_back({item, SamplingStrategy::Bsdf, true, false});
    else if (item == "light") out.push_back({item, SamplingStrategy::Light, true, false});
    else if (item == "env-uniform") out.push_back({item, SamplingStrategy::Mis, false, true});
    else if (item == "env-importance") out.push_back({item, SamplingStrategy::Mis, true, true});
    else
      throw std::invalid_argument("unknown strategy '" + item +
                                  "' (choose from mis, bsdf, light, env-uniform, env-importance)");
  }
  if (out.empty()) throw std::invalid_argument("no strategy given");
  return out;
}

Image render_image(const Scene& scene, const std::string& backend_name, const StrategySpec& strategy, int spp,
                   int max_depth, int rr_depth, std::uint64_t seed, double* seconds) {
  std::unique_ptr<Backend> backend = make_backend(backend_name);
  {
    const ScopedFlushDenormals ftz;
    backend->build(scene.geometry);
  }
  return render_with(scene, *backend, strategy, spp, max_depth, rr_depth, seed, seconds);
}

std::vector<ConvergeSeries> run_study(const Scene& scene, const Image& reference, const StudySettings& settings,
                                      const std::function<void(const std::string&)>& log) {
  std::vector<ConvergeSeries> all;
  for (const std::string& backend_name : settings.backends) {
    std::unique_ptr<Backend> backend = make_backend(backend_name);
    const auto build_start = std::chrono::steady_clock::now();
    {
      const ScopedFlushDenormals ftz;
      backend->build(scene.geometry);
    }
    const double build_seconds = seconds_since(build_start);
    for (const StrategySpec& strategy : settings.strategies) {
      ConvergeSeries series;
      series.backend = backend_name;
      series.strategy = strategy.name;
      series.build_seconds = build_seconds;
      double used = 0.0;
      for (int spp = 1; spp <= settings.max_spp; spp *= 2) {
        if (series.points.size() >= 2 && used + 2.0 * series.points.back().seconds > settings.budget_seconds) break;
        ConvergePoint p;
        p.spp = spp;
        series.last_image = render_with(scene, *backend, strategy, spp, settings.max_depth, settings.rr_depth,
                                        settings.seed, &p.seconds);
        p.error = compute_error(series.last_image, reference);
        used += p.seconds;
        series.points.push_back(p);
        log(fmt::format("{:>12} {:>14} {:>7} spp {:>9.3f} s  relMSE {:.4e}  RMSE {:.4e}  MAE {:.4e}", backend_name,
                        strategy.name, spp, p.seconds, p.error.rel_mse, p.error.rmse, p.error.mae));
        if (spp > settings.max_spp / 2) break;
      }
      std::vector<double> t, n, e;
      for (const ConvergePoint& p : series.points) {
        t.push_back(p.seconds);
        n.push_back(p.spp);
        e.push_back(p.error.rel_mse);
      }
      series.rel_mse_fit = fit_power_law(t, e);
      series.rel_mse_spp_fit = fit_power_law(n, e);
      all.push_back(std::move(series));
    }
  }
  return all;
}

}  // namespace twinray::converge
