#pragma once
// Error of a rendered image against a reference, averaged over every pixel and colour channel:
//   relMSE = mean((x - r)^2 / (r^2 + kRelMseEpsilon))   relative mean squared error
//   RMSE   = sqrt(mean((x - r)^2))
//   MAE    = mean(|x - r|)
// For an unbiased Monte Carlo estimator every one of these squared errors falls as 1/samples (RMSE and MAE
// as 1/sqrt(samples)), so log(relMSE) against log(time) has slope -1.

#include "core/image/image.h"

namespace twinray::converge {

// Keeps relMSE finite on black reference pixels, and keeps near-black pixels (where the reference itself
// is mostly noise) from dominating the mean. 0.01 is the usual choice in the denoising literature; with
// radiance around 0.1 to 10 it changes the relative error of lit pixels by under 1%.
inline constexpr double kRelMseEpsilon = 1e-2;

struct ErrorMetrics {
  double rel_mse = 0.0;
  double rmse = 0.0;
  double mae = 0.0;
};

// Throws std::invalid_argument when the sizes or channel counts differ. Compares the first three channels
// (RGB); a one-channel image is compared channel 0 against channel 0.
ErrorMetrics compute_error(const Image& image, const Image& reference);

// Per-pixel relative squared error (mean over the channels, same epsilon), one channel: for the
// false-colour error image.
Image relative_squared_error_image(const Image& image, const Image& reference);

// |image - reference| per pixel and channel (RGB): the difference image.
Image absolute_difference_image(const Image& image, const Image& reference);

}  // namespace twinray::converge
