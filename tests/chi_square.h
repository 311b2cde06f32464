#pragma once
// Pearson's chi-square goodness-of-fit test shared by the sampling tests.
//
// Bins expecting fewer than 5 samples are pooled, because the chi-square approximation of the statistic
// needs about 5 expected counts per bin. The critical value is the chi-square quantile at significance 1e-6
// (Wilson-Hilferty approximation, accurate to a fraction of a percent for dof >= 10): with the fixed seeds
// used here the test is deterministic, and for an arbitrary seed a correct sampler would fail it once in a
// million runs, while a sampler whose density is off by a few percent in a handful of bins fails it
// reliably at these sample counts. Any sample landing in a bin of expected count 0 fails outright.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace twinray::testing {

inline ::testing::AssertionResult chi_square_accepts(const std::vector<double>& observed,
                                                     const std::vector<double>& expected) {
  double pooled_obs = 0.0, pooled_exp = 0.0, statistic = 0.0;
  int bins = 0;
  for (std::size_t i = 0; i < observed.size(); ++i) {
    if (expected[i] == 0.0 && observed[i] > 0.0)
      return ::testing::AssertionFailure() << observed[i] << " samples in bin " << i << " of probability 0";
    if (expected[i] < 5.0) {
      pooled_obs += observed[i];
      pooled_exp += expected[i];
      continue;
    }
    statistic += (observed[i] - expected[i]) * (observed[i] - expected[i]) / expected[i];
    ++bins;
  }
  if (pooled_exp >= 5.0) {
    statistic += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / pooled_exp;
    ++bins;
  }
  const double dof = bins - 1;
  const double z = 4.753424;  // standard normal quantile for a one-sided 1e-6 tail
  const double a = 2.0 / (9.0 * dof);
  const double critical = dof * std::pow(1.0 - a + z * std::sqrt(a), 3.0);
  if (statistic <= critical) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "chi-square " << statistic << " > critical " << critical << " (dof "
                                       << dof << ")";
}

}  // namespace twinray::testing
