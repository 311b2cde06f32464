#include "harness/compare/image_comparison.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace twinray::compare {

namespace {

void require_rgb(const Image& img, const char* what) {
  if (img.channels != 3) throw std::invalid_argument(std::string(what) + " is not an RGB image");
}

void require_same_size(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) throw std::invalid_argument("the images differ in size");
}

void check(const NoisyImage& img) {
  require_rgb(img.mean, "a mean image");
  require_rgb(img.variance_of_mean, "a variance image");
  require_same_size(img.mean, img.variance_of_mean);
}

// Inverse of the two-sided normal tail: the z with P(|Z| > z) = p, by bisection on erfc (monotonic).
double two_sided_normal_quantile(double p) {
  double lo = 0.0, hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (std::erfc(mid / std::sqrt(2.0)) > p) lo = mid;
    else hi = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

ChannelMeans channel_means(const NoisyImage& image) {
  check(image);
  ChannelMeans m;
  const double n = static_cast<double>(image.mean.pixel_count());
  if (n == 0.0) return m;
  std::array<double, 3> var{};
  for (std::size_t i = 0; i < image.mean.pixel_count(); ++i)
    for (std::size_t c = 0; c < 3; ++c) {
      m.mean[c] += image.mean.data[3 * i + c];
      var[c] += image.variance_of_mean.data[3 * i + c];
    }
  for (std::size_t c = 0; c < 3; ++c) {
    m.mean[c] /= n;
    m.standard_error[c] = std::sqrt(var[c]) / n;
  }
  return m;
}

double expected_rel_mse(const NoisyImage& image, const Image& truth) {
  check(image);
  require_rgb(truth, "the reference");
  require_same_size(image.mean, truth);
  double sum = 0.0;
  for (std::size_t i = 0; i < truth.data.size(); ++i) {
    const double r = truth.data[i];
    sum += image.variance_of_mean.data[i] / (r * r + kRelMseEpsilon);
  }
  return truth.data.empty() ? 0.0 : sum / static_cast<double>(truth.data.size());
}

double rel_mse(const Image& a, const Image& reference) {
  require_rgb(a, "the image");
  require_rgb(reference, "the reference");
  require_same_size(a, reference);
  double sum = 0.0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    const double r = reference.data[i];
    const double d = static_cast<double>(a.data[i]) - r;
    sum += d * d / (r * r + kRelMseEpsilon);
  }
  return a.data.empty() ? 0.0 : sum / static_cast<double>(a.data.size());
}

double bonferroni_threshold(int tests) { return two_sided_normal_quantile(kFamilyFalseAlarm / std::max(1, tests)); }

Comparison compare_images(const NoisyImage& a, const NoisyImage& b, int grid) {
  check(a);
  check(b);
  require_same_size(a.mean, b.mean);
  const int w = a.mean.width, h = a.mean.height;
  const int gx = std::max(1, std::min(grid, w)), gy = std::max(1, std::min(grid, h));
  Comparison out;
  out.threshold = bonferroni_threshold(gx * gy * 3);
  for (int ry = 0; ry < gy; ++ry) {
    for (int rx = 0; rx < gx; ++rx) {
      const int x0 = rx * w / gx, x1 = (rx + 1) * w / gx, y0 = ry * h / gy, y1 = (ry + 1) * h / gy;
      for (int c = 0; c < 3; ++c) {
        double diff = 0.0, var = 0.0, level = 0.0;
        for (int y = y0; y < y1; ++y)
          for (int x = x0; x < x1; ++x) {
            diff += static_cast<double>(a.mean.at(x, y, c)) - static_cast<double>(b.mean.at(x, y, c));
            var += static_cast<double>(a.variance_of_mean.at(x, y, c)) + static_cast<double>(b.variance_of_mean.at(x, y, c));
            level += 0.5 * std::abs(static_cast<double>(a.mean.at(x, y, c)) + static_cast<double>(b.mean.at(x, y, c)));
          }
        const double n = static_cast<double>((x1 - x0) * (y1 - y0));
        if (n == 0.0) continue;
        const double floor = kRelativeFloor * level / n;
        RegionDifference r{x0, y0, x1, y1, c, diff / n, std::sqrt(var / (n * n) + floor * floor), 0.0};
        // A region where both images are exactly equal and noiseless (black) agrees; any difference without
        // noise to explain it is infinitely significant.
        if (r.standard_error > 0.0) r.z = r.difference / r.standard_error;
        else if (r.difference != 0.0) r.z = std::copysign(HUGE_VAL, r.difference);
        out.max_abs_z = std::max(out.max_abs_z, std::abs(r.z));
        out.regions.push_back(r);
        if (std::abs(r.z) > out.threshold) out.differing.push_back(r);
      }
    }
  }
  std::sort(out.differing.begin(), out.differing.end(),
            [](const RegionDifference& p, const RegionDifference& q) { return std::abs(p.z) > std::abs(q.z); });
  out.agree = out.differing.empty();

  double between = 0.0, noise = 0.0;
  for (std::size_t i = 0; i < a.mean.data.size(); ++i) {
    const double r = 0.5 * (static_cast<double>(a.mean.data[i]) + static_cast<double>(b.mean.data[i]));
    const double d = static_cast<double>(a.mean.data[i]) - static_cast<double>(b.mean.data[i]);
    const double denom = r * r + kRelMseEpsilon;
    between += d * d / denom;
    noise += (static_cast<double>(a.variance_of_mean.data[i]) + static_cast<double>(b.variance_of_mean.data[i])) / denom;
  }
  const double count = static_cast<double>(std::max<std::size_t>(1, a.mean.data.size()));
  out.rel_mse_between = between / count;
  out.rel_mse_between_noise = noise / count;
  return out;
}

Image region_z_image(const Comparison& c, int width, int height) {
  Image out(width, height, 1);
  for (const RegionDifference& r : c.regions)
    for (int y = r.y0; y < r.y1 && y < height; ++y)
      for (int x = r.x0; x < r.x1 && x < width; ++x)
        out.at(x, y) = std::max(out.at(x, y), static_cast<float>(std::min(std::abs(r.z), 1e30)));
  return out;
}

Image pixel_z_image(const NoisyImage& a, const NoisyImage& b) {
  check(a);
  check(b);
  require_same_size(a.mean, b.mean);
  Image out(a.mean.width, a.mean.height, 1);
  for (std::size_t i = 0; i < a.mean.pixel_count(); ++i) {
    double d = 0.0, v = 0.0;
    for (std::size_t c = 0; c < 3; ++c) {
      d += std::abs(static_cast<double>(a.mean.data[3 * i + c]) - static_cast<double>(b.mean.data[3 * i + c]));
      v += static_cast<double>(a.variance_of_mean.data[3 * i + c]) + static_cast<double>(b.variance_of_mean.data[3 * i + c]);
    }
    out.data[i] = v > 0.0 ? static_cast<float>((d / 3.0) / std::sqrt(v / 3.0)) : (d > 0.0 ? 1e30f : 0.0f);
  }
  return out;
}

}  // namespace twinray::compare
