#pragma once
// A convergence study: error against wall time for every (backend, strategy) pair, at doubling sample
// counts, against one reference image.
//
// Sampling: the renderer draws sample s of pixel p from Rng::keyed(seed, p, s), so a study render at N spp
// and a reference rendered with the same seed would share their first N samples and the error would be
// underestimated. The reference therefore always uses a seed derived from (and different from) the
// study's, kReferenceSeedOffset away.

#include "harness/converge/error_metrics.h"
#include "harness/converge/slope_fit.h"
#include "core/image/image.h"
#include "core/render/integrator.h"
#include "core/scene/scene.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace twinray::converge {

inline constexpr std::uint64_t kReferenceSeedOffset = 0x5eed'0000'0000'0001ull;

// A strategy as named on the command line: mis, bsdf, light (area and environment lights sampled as the
// renderer's SamplingStrategy says, environment importance sampling on), env-uniform and env-importance
// (MIS, environment directions drawn uniformly or from the map's importance tables).
struct StrategySpec {
  std::string name;
  SamplingStrategy strategy = SamplingStrategy::Mis;
  bool env_importance = true;
  bool needs_environment_map = false;
};

// Throws std::invalid_argument naming the bad item and the choices.
std::vector<StrategySpec> parse_strategies(const std::string& list);

struct StudySettings {
  std::vector<std::string> backends;
  std::vector<StrategySpec> strategies;
  double budget_seconds = 10.0;  // per (backend, strategy)
  int max_spp = 1 << 20;         // no point above this spp (a fraction of the reference's, see cmd_converge)
  int max_depth = -1;
  int rr_depth = 5;
  std::uint64_t seed = 0;
};

struct ConvergePoint {
  int spp = 0;
  double seconds = 0.0;  // wall time of this render alone (setup + rendering), all threads
  ErrorMetrics error;
};

struct ConvergeSeries {
  std::string backend;
  std::string strategy;
  std::vector<ConvergePoint> points;
  PowerLawFit rel_mse_fit;      // log relMSE against log seconds (the plotted slope)
  PowerLawFit rel_mse_spp_fit;  // log relMSE against log spp (free of timing noise and fixed costs)
  Image last_image;         // the render of the last point
  double build_seconds = 0.0;
};

// Doubling spp 1, 2, 4, ... per series. A series stops when the next render (predicted to take twice the
// last one) would take its total past the budget, or at max_spp; it always has at least two points, so a
// slope exists, unless max_spp is 1.
std::vector<ConvergeSeries> run_study(const Scene& scene, const Image& reference, const StudySettings& settings,
                                      const std::function<void(const std::string&)>& log);

// One render of `scene` with `backend_name` into an in-memory image (mean radiance, RGB); returns its
// wall time in `seconds` when not null. Uses the current TBB concurrency.
Image render_image(const Scene& scene, const std::string& backend_name, const StrategySpec& strategy, int spp,
                   int max_depth, int rr_depth, std::uint64_t seed, double* seconds = nullptr);

}  // namespace twinray::converge
