#pragma once
// `twinray grade --time-scale auto`: how much slower than the reference machine this machine runs now, as a
// coarse factor for every time limit of a suite (docs/grading.md, "Slower machines").
//
// The measure: twinray's own `bvh` backend builds a fixed scene (a soup of 10,000 triangles, seed 1) and traces
// a fixed set of 50,000 rays on one thread, five times; the median wall-clock time against the same workload's
// time on the reference machine. Wall clock on purpose: the limits are wall clock, so a machine that is busy
// (other graders, other jobs) counts as slow as much as one with a slower processor.
//
// The factor is fair only if it is stable: the ratio is quantised to a coarse ladder (1, 1.5, 2, 3, 4, 6, 8, 12,
// 16, 24, 32, 48, 64, 100) after a quarter is forgiven for noise, and it never goes below 1, so a fast machine
// never tightens a suite's limits and two runs on the same machine under the same load get the same factor
// (a run whose ratio lies within noise of a rung can land on either neighbour; both only loosen limits).

namespace twinray::grade {

struct TimeCalibration {
  double reference_seconds = 0.0;  // the workload on the reference machine (kReferenceWorkloadSeconds)
  double measured_seconds = 0.0;   // the median here, now
  double scale = 1.0;              // the factor applied to every time limit
};

// The median of the workload's five runs on the 2-core reference machine (AMD EPYC Zen 4, shared and busy, load
// average 9 to 11, Release build; five medians 0.36 to 0.50 s), where the bundled suites' limits and budgets were set.
inline constexpr double kReferenceWorkloadSeconds = 0.35;

// The rung of the ladder for a measured / reference ratio (see above): 1 up to a ratio of 1.25, then the
// smallest rung at least ratio / 1.25, at most 100.
double quantised_time_scale(double ratio);

// Runs the workload (about a second here) and returns the factor.
TimeCalibration calibrate_time_scale();

}  // namespace twinray::grade
