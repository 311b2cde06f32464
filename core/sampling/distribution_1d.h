#pragma once
// Sampling proportional to a list of non-negative weights: as a discrete distribution over indices, or as a
// piecewise-constant density on [0,1) with one equal-width bin per weight.
//
// Precision: the CDF is accumulated and stored in double. A float running sum over a 1k x 512 map loses
// the small weights entirely once the sum is ~2^24 times larger, giving texels a nonzero pmf() that
// sampling can never reach (bias). With double every bin whose weight is at least ~2^-53 of the total gets
// a CDF step.
//
// Zero weights: a bin of weight 0 has an empty CDF interval [cdf[i], cdf[i+1]) and the search below looks
// for cdf[i] <= u < cdf[i+1], so it is never returned, however long the flat run of equal CDF values is.
//
// All-zero weights: the distribution falls back to uniform (pmf 1/n, pdf 1) so a caller never divides by a
// zero pdf; integral() still reports 0 so the caller can tell that nothing is there to sample.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace twinray {

class Distribution1D {
 public:
  // weights: finite and >= 0, at least one; throws std::invalid_argument otherwise.
  explicit Distribution1D(std::span<const float> weights) : weights_(weights.begin(), weights.end()) {
    if (weights_.empty()) throw std::invalid_argument("Distribution1D: no weights");
    cdf_.resize(weights_.size() + 1);
    double running = 0.0;
    cdf_[0] = 0.0;
    for (std::size_t i = 0; i < weights_.size(); ++i) {
      const float w = weights_[i];
      if (!std::isfinite(w) || w < 0.0f)
        throw std::invalid_argument("Distribution1D: weight " + std::to_string(i) + " is negative or not finite");
      running += static_cast<double>(w);
      cdf_[i + 1] = running;
    }
    sum_ = running;
    const double n = static_cast<double>(weights_.size());
    if (sum_ > 0.0) {
      for (double& c : cdf_) c /= sum_;
    } else {
      for (std::size_t i = 0; i < cdf_.size(); ++i) cdf_[i] = static_cast<double>(i) / n;
    }
    cdf_.back() = 1.0;  // exact, whatever the division rounded to
    first_positive_ = 0;
    while (first_positive_ + 1 < weights_.size() && !(cdf_[first_positive_ + 1] > cdf_[first_positive_]))
      ++first_positive_;
    last_positive_ = weights_.size() - 1;
    while (last_positive_ > 0 && !(cdf_[last_positive_ + 1] > cdf_[last_positive_])) --last_positive_;
  }

  std::size_t size() const { return weights_.size(); }
  // Integral of the piecewise-constant function over [0,1): sum of weights / size(). 0 when all are zero.
  double integral() const { return sum_ / static_cast<double>(weights_.size()); }
  double weight_sum() const { return sum_; }
  float weight(std::size_t i) const { return weights_[i]; }

  // Probability of index i: weight / sum (1/n for the all-zero fallback).
  float pmf(std::size_t i) const {
    if (sum_ > 0.0) return static_cast<float>(static_cast<double>(weights_[i]) / sum_);
    return static_cast<float>(1.0 / static_cast<double>(weights_.size()));
  }

  // Index i with probability pmf(i), u in [0,1). u_remapped, if given, receives (u - cdf[i]) / pmf(i) in
  // [0,1): a fresh uniform that can drive a further choice inside the bin.
  std::size_t sample_discrete(float u, float* pmf_out, float* u_remapped = nullptr) const {
    const std::size_t i = find_bin(static_cast<double>(u));
    if (pmf_out) *pmf_out = pmf(i);
    if (u_remapped) *u_remapped = remap(static_cast<double>(u), i);
    return i;
  }

  // x in [0,1) with density pdf_continuous(x); offset, if given, receives the bin of x.
  float sample_continuous(float u, float* pdf_out, std::size_t* offset = nullptr) const {
    const std::size_t i = find_bin(static_cast<double>(u));
    if (offset) *offset = i;
    if (pdf_out) *pdf_out = bin_pdf(i);
    const double du = static_cast<double>(remap(static_cast<double>(u), i));
    float x = static_cast<float>((static_cast<double>(i) + du) / static_cast<double>(weights_.size()));
    // Rounding must not carry x into the next bin: pdf_continuous(x) has to describe the bin it came from.
    while (x > 0.0f && bin_of(x) > i) x = std::nextafter(x, 0.0f);
    return x;
  }

  // Density on [0,1) at x; x outside [0,1) is clamped to the first/last bin.
  float pdf_continuous(float x) const { return bin_pdf(bin_of(x)); }

  // Bin containing x in [0,1), clamped.
  std::size_t bin_of(float x) const {
    const float scaled = x * static_cast<float>(weights_.size());
    if (!(scaled > 0.0f)) return 0;
    return std::min(static_cast<std::size_t>(scaled), weights_.size() - 1);
  }

  // Bytes held by the tables (for memory reports).
  std::size_t memory_bytes() const {
    return weights_.capacity() * sizeof(float) + cdf_.capacity() * sizeof(double) + sizeof(*this);
  }

 private:
  float bin_pdf(std::size_t i) const {
    if (sum_ > 0.0)
      return static_cast<float>(static_cast<double>(weights_[i]) * static_cast<double>(weights_.size()) / sum_);
    return 1.0f;
  }

  // The i with cdf[i] <= u < cdf[i+1]; u outside [0,1) (a caller bug, or 1.0 from rounding) is clamped to
  // the first/last bin that has positive probability, so a zero-weight bin can never come out.
  std::size_t find_bin(double u) const {
    if (!(u >= 0.0)) return first_positive_;  // also catches NaN
    // upper_bound: first cdf entry > u. cdf[0] = 0 <= u, so it is at index >= 1.
    const auto it = std::upper_bound(cdf_.begin(), cdf_.end(), u);
    if (it == cdf_.end()) return last_positive_;
    return static_cast<std::size_t>(it - cdf_.begin()) - 1;
  }

  float remap(double u, std::size_t i) const {
    const double width = cdf_[i + 1] - cdf_[i];
    const double r = width > 0.0 ? (u - cdf_[i]) / width : 0.0;
    if (!(r > 0.0)) return 0.0f;  // also NaN u
    // Largest float below 1: a remapped uniform must stay in [0,1) like the input.
    return std::min(static_cast<float>(r), 0x1.fffffep-1f);
  }

  std::vector<float> weights_;
  std::vector<double> cdf_;  // size n + 1, cdf_[0] = 0, cdf_[n] = 1
  double sum_ = 0.0;
  std::size_t first_positive_ = 0;
  std::size_t last_positive_ = 0;
};

}  // namespace twinray
