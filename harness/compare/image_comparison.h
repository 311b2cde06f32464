#pragma once
// Do two noisy renders of the same scene agree within their noise? The statistics of `twinray compare`.
//
// Each render comes as its mean image and the per-pixel variance of that mean (both renderers render in
// independent batches, and the variance is the batches' sample variance / batch count: valid for any
// sampler, low-discrepancy ones included, which a per-sample variance would overestimate).
//
// Verdict: the image is cut into a grid of regions (kRegionGrid x kRegionGrid). In every region and channel
// the mean difference d of the two images is compared with its standard error s = sqrt(sum over the
// region's pixels of (var_a + var_b)) / pixels; the images differ when some |d| / s exceeds the threshold
// below, and the regions that do are listed. With regions of hundreds of pixels the sums make d / s close
// to a standard normal under agreement, whatever the per-pixel distributions.
//
// Numerical floor: where both images are free of noise (a directly seen constant sky, a black region) the
// standard error is 0 and any rounding difference would be infinitely significant. Both renderers compute in
// 32-bit float and round constants differently by a few ulps, so the standard error of every region is
// floored at kRelativeFloor times the region's mean value (1e-5: about 100 float ulps, far below any
// difference that a scene change produces).
//
// Threshold: a family-wise false alarm rate of 1e-3 over all region-channel tests (Bonferroni): for 16 x 16
// regions and 3 channels, 768 tests, the two-sided normal quantile of 1e-3 / 768 is 4.83. A difference of a
// few standard errors in one region out of hundreds is what noise does; 4.83 happens by chance once in a
// thousand comparisons.

#include "core/image/image.h"

#include <array>
#include <vector>

namespace twinray::compare {

inline constexpr int kRegionGrid = 16;
inline constexpr double kFamilyFalseAlarm = 1e-3;
inline constexpr double kRelativeFloor = 1e-5;

// relMSE's regulariser, as in harness/converge/error_metrics.h.
inline constexpr double kRelMseEpsilon = 1e-2;

struct NoisyImage {
  Image mean;              // RGB
  Image variance_of_mean;  // RGB, per pixel
};

struct ChannelMeans {
  std::array<double, 3> mean{};
  std::array<double, 3> standard_error{};  // of the image mean, from the per-pixel variances
};

ChannelMeans channel_means(const NoisyImage& image);

// The relMSE an unbiased render with these variances has in expectation against the truth `truth`:
// mean over pixels and channels of var / (truth^2 + eps). What a render's noise alone contributes.
double expected_rel_mse(const NoisyImage& image, const Image& truth);

// relMSE of a against reference r: mean((a - r)^2 / (r^2 + eps)) over pixels and RGB.
double rel_mse(const Image& a, const Image& reference);

struct RegionDifference {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // pixel rectangle [x0, x1) x [y0, y1)
  int channel = 0;
  double difference = 0.0;      // mean of a - b over the region
  double standard_error = 0.0;  // of that mean
  double z = 0.0;               // difference / standard_error (0 when both are 0)
};

struct Comparison {
  bool agree = true;
  double threshold = 0.0;                      // |z| above which a region differs
  double max_abs_z = 0.0;
  std::vector<RegionDifference> regions;       // every region and channel
  std::vector<RegionDifference> differing;     // |z| > threshold, largest |z| first
  // relMSE of a against b with b's mean as the reference for the denominator, minus what the noise of both
  // explains: about 0 when the images agree, the relMSE of the bias otherwise.
  double rel_mse_between = 0.0;
  double rel_mse_between_noise = 0.0;
  double rel_mse_excess() const { return rel_mse_between - rel_mse_between_noise; }
};

// The Bonferroni threshold for `tests` two-sided tests at family rate kFamilyFalseAlarm.
double bonferroni_threshold(int tests);

// Throws std::invalid_argument when the images differ in size or are not RGB.
Comparison compare_images(const NoisyImage& a, const NoisyImage& b, int grid = kRegionGrid);

// Per-region |z| (the largest over the channels) painted over the region's pixels, one channel: for the
// false-colour map of where the images differ.
Image region_z_image(const Comparison& c, int width, int height);

// Per-pixel |a - b| averaged over RGB divided by the standard error of that pixel's difference, one channel.
Image pixel_z_image(const NoisyImage& a, const NoisyImage& b);

}  // namespace twinray::compare
