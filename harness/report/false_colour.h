#pragma once
// False-colour images of scalar fields (per-pixel error, per-pixel traversal cost) for the reports.

#include "core/image/image.h"

#include <glm/vec3.hpp>

namespace twinray::report {

// Maps t in [0, 1] (clamped; NaN -> 0) to a colour ramp from dark blue through magenta and orange to pale
// yellow: monotonic in lightness, so the order of values survives greyscale printing and most colour
// blindness. Returned in sRGB-encoded [0, 1] (display values).
glm::vec3 colour_ramp_srgb(float t);

struct ScalarRange {
  double lo = 0.0, hi = 1.0;
  bool log = false;  // map log10(v) between log10(lo) and log10(hi) (lo must be > 0)
};

// One channel in, three channels out, as LINEAR values: write_png applies the sRGB curve, which then
// reproduces the ramp's display colours exactly.
Image false_colour(const Image& scalar, const ScalarRange& range);

// The range [p-th smallest, q-th smallest] of the finite positive values (percentiles 0..1), for robust
// colour scales that a few outliers do not wash out. Returns {0, 1} when there are none.
ScalarRange percentile_range(const Image& scalar, double p, double q, bool log);

}  // namespace twinray::report
