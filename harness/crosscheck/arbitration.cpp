#include "harness/crosscheck/arbitration.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <optional>

namespace twinray::crosscheck {

namespace {

// One backend's rulings on one ray, kept compact until the ordered reduction.
struct Rulings {
  bool closest_ruled = false, occlusion_ruled = false;
  arbiter::Reason closest_reason = arbiter::Reason::Agrees, occlusion_reason = arbiter::Reason::Agrees;
  double t_rel_error = -1.0;
  std::optional<WrongAnswer> wrong_closest, wrong_occlusion;
};

}  // namespace

void accumulate(ArbiterTally& total, const ArbiterTally& part, std::size_t max_examples) {
  total.ruled += part.ruled;
  total.wrong += part.wrong;
  total.max_t_rel_error = std::max(total.max_t_rel_error, part.max_t_rel_error);
  for (std::size_t k = 0; k < total.reasons.size(); ++k) total.reasons[k] += part.reasons[k];
  for (const WrongAnswer& w : part.examples)
    if (total.examples.size() < max_examples) total.examples.push_back(w);
}

ArbitrationResult arbitrate(const arbiter::Arbiter& arbiter, std::span<const Ray> rays,
                            std::span<const BackendAnswers> answers, std::span<const std::uint8_t> disputes,
                            std::size_t max_rays, std::size_t max_examples) {
  const auto start = std::chrono::steady_clock::now();
  ArbitrationResult result;
  result.backends.resize(answers.size());
  std::vector<std::size_t> ruled;
  for (std::size_t i = 0; i < disputes.size(); ++i) {
    if (disputes[i] == 0) continue;
    ++result.disputed_rays;
    if (ruled.size() < max_rays) ruled.push_back(i);
  }
  result.ruled_rays = ruled.size();

  const std::size_t n_backends = answers.size();
  std::vector<Rulings> rulings(ruled.size() * n_backends);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ruled.size(), 16), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t j = range.begin(); j != range.end(); ++j) {
      const std::size_t i = ruled[j];
      const Ray& ray = rays[i];
      for (std::size_t k = 0; k < n_backends; ++k) {
        const BackendAnswers& a = answers[k];
        Rulings& out = rulings[j * n_backends + k];
        if ((disputes[i] & kClosestDisputed) != 0) {
          arbiter::Ruling r = arbiter.rule_closest(ray, a.closest[i], a.traits);
          out.closest_ruled = true;
          out.closest_reason = r.reason;
          out.t_rel_error = r.t_rel_error;
          if (!r.right) out.wrong_closest = WrongAnswer{i, ray, false, a.closest[i], false, std::move(r)};
        }
        if ((disputes[i] & kOcclusionDisputed) != 0) {
          const bool answered = a.occluded[i] != 0;
          arbiter::Ruling r = arbiter.rule_occluded(ray, answered, a.traits);
          out.occlusion_ruled = true;
          out.occlusion_reason = r.reason;
          if (!r.right) out.wrong_occlusion = WrongAnswer{i, ray, true, a.closest[i], answered, std::move(r)};
        }
      }
    }
  });

  for (std::size_t j = 0; j < ruled.size(); ++j) {
    for (std::size_t k = 0; k < n_backends; ++k) {
      const Rulings& r = rulings[j * n_backends + k];
      ArbiterTally& t = result.backends[k];
      if (r.closest_ruled) {
        ++t.ruled;
        ++t.reasons[static_cast<std::size_t>(r.closest_reason)];
        t.max_t_rel_error = std::max(t.max_t_rel_error, r.t_rel_error);
      }
      if (r.occlusion_ruled) {
        ++t.ruled;
        ++t.reasons[static_cast<std::size_t>(r.occlusion_reason)];
      }
      for (const std::optional<WrongAnswer>* w : {&r.wrong_closest, &r.wrong_occlusion}) {
        if (!w->has_value()) continue;
        ++t.wrong;
        if (t.examples.size() < max_examples) t.examples.push_back(**w);
      }
    }
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace twinray::crosscheck
