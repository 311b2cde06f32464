#pragma once
// How measured cost grows with the triangle count N, against the textbook expectation:
//   build time      ~ N log N    (binned SAH: log N levels of linear passes)
//   nodes per ray   ~ log N      (a balanced tree over a surface of fixed extent)
//   bytes per prim  ~ constant   (nodes and primitive references are linear in N)
// Each comparison fits the measurement over the same N values as the model and states whether it
// departs, so the report's scaling text is computed, not written by hand.

#include <string>
#include <vector>

namespace twinray::report {

struct ScalingCheck {
  std::string quantity;    // "build time", "nodes per ray", "bytes per primitive"
  std::string series;      // "bvh sphere"
  double measured = 0.0;   // log-log slope (exponent) of the measurement
  double expected = 0.0;   // log-log slope of the model over the same N
  bool departs = false;
  std::string verdict;     // one sentence
};

// Exponent tolerances: build time and nodes per ray depart when |measured - expected| > 0.15;
// bytes per primitive departs when its largest and smallest values differ by more than 25%. Wide enough
// for timing noise on a shared machine, tight enough to flag a quadratic build or a linear traversal.
inline constexpr double kExponentTolerance = 0.15;
inline constexpr double kFlatTolerance = 0.25;

ScalingCheck check_n_log_n(const std::string& quantity, const std::string& series, const std::vector<double>& n,
                           const std::vector<double>& value);
ScalingCheck check_log_n(const std::string& quantity, const std::string& series, const std::vector<double>& n,
                         const std::vector<double>& value);
ScalingCheck check_flat(const std::string& quantity, const std::string& series, const std::vector<double>& n,
                        const std::vector<double>& value);

}  // namespace twinray::report
