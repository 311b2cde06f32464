#include "harness/report/scaling.h"

#include "harness/converge/slope_fit.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

namespace twinray::report {

namespace {

ScalingCheck compare(const std::string& quantity, const std::string& series, const std::vector<double>& n,
                     const std::vector<double>& value, const std::vector<double>& model, const char* model_name) {
  ScalingCheck c;
  c.quantity = quantity;
  c.series = series;
  const converge::PowerLawFit measured = converge::fit_power_law(n, value);
  const converge::PowerLawFit expected = converge::fit_power_law(n, model);
  if (!measured.valid() || !expected.valid()) {
    c.verdict = fmt::format("{} of {}: too few sizes to tell", quantity, series);
    return c;
  }
  c.measured = measured.slope;
  c.expected = expected.slope;
  c.departs = std::abs(c.measured - c.expected) > kExponentTolerance;
  const auto [lo, hi] = std::minmax_element(n.begin(), n.end());
  c.verdict = fmt::format("{} of {} grows as N^{:.2f} from N = {:.0f} to {:.0f}; {} predicts N^{:.2f} over that range: {}",
                          quantity, series, c.measured, *lo, *hi, model_name, c.expected,
                          c.departs ? (c.measured > c.expected ? "grows FASTER than expected"
                                                               : "grows SLOWER than expected")
                                    : "as expected");
  return c;
}

}  // namespace

ScalingCheck check_n_log_n(const std::string& quantity, const std::string& series, const std::vector<double>& n,
                           const std::vector<double>& value) {
  std::vector<double> model;
  for (double x : n) model.push_back(x * std::log2(std::max(x, 2.0)));
  return compare(quantity, series, n, value, model, "N log N");
}

ScalingCheck check_log_n(const std::string& quantity, const std::string& series, const std::vector<double>& n,
                         const std::vector<double>& value) {
  std::vector<double> model;
  for (double x : n) model.push_back(std::log2(std::max(x, 2.0)));
  return compare(quantity, series, n, value, model, "log N");
}

ScalingCheck check_flat(const std::string& quantity, const std::string& series, const std::vector<double>& n,
                        const std::vector<double>& value) {
  ScalingCheck c;
  c.quantity = quantity;
  c.series = series;
  std::vector<double> positive;
  for (double v : value)
    if (v > 0.0) positive.push_back(v);
  if (positive.size() < 2 || n.size() < 2) {
    c.verdict = fmt::format("{} of {}: too few sizes to tell", quantity, series);
    return c;
  }
  const auto [lo, hi] = std::minmax_element(positive.begin(), positive.end());
  c.measured = converge::fit_power_law(n, value).slope;
  c.expected = 0.0;
  c.departs = *hi > (1.0 + kFlatTolerance) * *lo;
  c.verdict = fmt::format("{} of {} stays between {:.1f} and {:.1f} (exponent {:.2f}): {}", quantity, series, *lo, *hi,
                          c.measured, c.departs ? "NOT flat" : "flat as expected");
  return c;
}

}  // namespace twinray::report
