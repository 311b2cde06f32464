#pragma once
// Least-squares line through (log x, log y): the exponent of a power law y = a x^slope. Used for the
// convergence rate (error against time, expected slope -1 for relMSE) and for the scaling exponents of
// the benchmark report (build time against N).

#include <span>

namespace twinray::converge {

struct PowerLawFit {
  double slope = 0.0;
  double intercept = 0.0;  // natural log of a
  double r_squared = 0.0;  // of the fit in log-log space
  int points = 0;          // points used (positive x and y only)
  bool valid() const { return points >= 2; }
};

// Points with x <= 0 or y <= 0 (or not finite) are skipped; fewer than two usable points, or all x equal,
// give an invalid fit (points < 2, slope 0).
PowerLawFit fit_power_law(std::span<const double> x, std::span<const double> y);

}  // namespace twinray::converge
