#include "harness/grade/scorecard.h"

namespace twinray::grade {

double Scorecard::score() const {
  double s = 0.0;
  for (const CheckResult& c : checks) s += c.points;
  return s;
}

double Scorecard::max_score() const {
  double s = 0.0;
  for (const CheckResult& c : checks) s += c.max_points;
  return s;
}

bool Scorecard::passed() const {
  for (const CheckResult& c : checks)
    if (c.fails_run()) return false;
  return true;
}

std::size_t Scorecard::count(Outcome o) const {
  std::size_t n = 0;
  for (const CheckResult& c : checks) n += c.outcome == o ? 1 : 0;
  return n;
}

}  // namespace twinray::grade
