#pragma once
// Sampling a 2D grid of non-negative weights: a marginal distribution over rows, then the conditional
// distribution of the chosen row over its columns. As a density it is piecewise constant on [0,1)^2 with
// one cell per weight; pdf values are with respect to area in [0,1]^2.
//
// Layout: row-major, weights[v * nu + u]; u (x) indexes columns, v (y) indexes rows, y = 0 is the first row.
// All-zero input samples uniformly (see Distribution1D).

#include "core/sampling/distribution_1d.h"

#include <glm/vec2.hpp>

#include <cstddef>
#include <span>
#include <stdexcept>
#include <vector>

namespace twinray {

class Distribution2D {
 public:
  // Throws std::invalid_argument on nu, nv < 1, a size mismatch, or a negative / non-finite weight.
  Distribution2D(std::span<const float> weights, int nu, int nv)
      : nu_(nu), nv_(nv), marginal_(check_and_row_integrals(weights, nu, nv, conditionals_)) {}

  int width() const { return nu_; }
  int height() const { return nv_; }
  // Integral of the piecewise-constant function over [0,1)^2 (0 when all weights are zero).
  double integral() const { return marginal_.integral(); }

  // A point in [0,1)^2 with density pdf(p).
  glm::vec2 sample(glm::vec2 u, float* pdf_out) const {
    std::size_t row = 0;
    const float y = marginal_.sample_continuous(u.y, nullptr, &row);
    std::size_t col = 0;
    const float x = conditionals_[row].sample_continuous(u.x, nullptr, &col);
    // One formula for sample() and pdf(), so the two agree bit for bit.
    if (pdf_out) *pdf_out = cell_pdf(col, row);
    return glm::vec2(x, y);
  }

  float pdf(glm::vec2 p) const {
    return cell_pdf(conditionals_[0].bin_of(p.x), marginal_.bin_of(p.y));
  }

  // A cell (column, row) with probability pmf(cell), plus a fresh uniform pair inside it; for callers that
  // map cells to non-square domains themselves (e.g. lat-long texels to solid angle).
  glm::ivec2 sample_cell(glm::vec2 u, float* pmf_out, glm::vec2* u_remapped = nullptr) const {
    glm::vec2 r(0.0f);
    const std::size_t row = marginal_.sample_discrete(u.y, nullptr, &r.y);
    const std::size_t col = conditionals_[row].sample_discrete(u.x, nullptr, &r.x);
    if (pmf_out) *pmf_out = pmf(static_cast<int>(col), static_cast<int>(row));
    if (u_remapped) *u_remapped = r;
    return glm::ivec2(static_cast<int>(col), static_cast<int>(row));
  }

  // Probability of cell (col, row): weight / total (1 / (nu nv) for all-zero input).
  float pmf(int col, int row) const {
    const double total = marginal_.weight_sum() * static_cast<double>(nu_);  // row integrals * nu = row sums
    if (total > 0.0)
      return static_cast<float>(static_cast<double>(conditionals_[static_cast<std::size_t>(row)].weight(
                                    static_cast<std::size_t>(col))) / total);
    return static_cast<float>(1.0 / (static_cast<double>(nu_) * static_cast<double>(nv_)));
  }

  std::size_t memory_bytes() const {
    std::size_t bytes = sizeof(*this) + marginal_.memory_bytes();
    for (const Distribution1D& c : conditionals_) bytes += c.memory_bytes();
    return bytes;
  }

 private:
  // density = weight / integral = weight * nu * nv / sum.
  float cell_pdf(std::size_t col, std::size_t row) const {
    const double integral = marginal_.integral();
    if (integral > 0.0) return static_cast<float>(static_cast<double>(conditionals_[row].weight(col)) / integral);
    return 1.0f;
  }

  // Builds the per-row conditionals and returns the row integrals that weight the marginal. The marginal
  // uses row *integrals* (sum / nu) so that marginal.integral() is the integral over the whole square.
  static Distribution1D check_and_row_integrals(std::span<const float> weights, int nu, int nv,
                                                std::vector<Distribution1D>& conditionals) {
    if (nu < 1 || nv < 1) throw std::invalid_argument("Distribution2D: grid must be at least 1 x 1");
    const auto su = static_cast<std::size_t>(nu), sv = static_cast<std::size_t>(nv);
    if (weights.size() != su * sv) throw std::invalid_argument("Distribution2D: weights.size() != nu * nv");
    conditionals.reserve(sv);
    std::vector<float> row_integrals(sv);
    for (std::size_t v = 0; v < sv; ++v) {
      conditionals.emplace_back(weights.subspan(v * su, su));
      row_integrals[v] = static_cast<float>(conditionals.back().integral());
    }
    return Distribution1D(row_integrals);
  }

  int nu_, nv_;
  std::vector<Distribution1D> conditionals_;  // declared before marginal_: filled while marginal_ is built
  Distribution1D marginal_;
};

}  // namespace twinray
