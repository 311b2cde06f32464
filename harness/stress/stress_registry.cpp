// The catalogue, assembled once from the family files in a fixed order.

#include "harness/stress/stress_case.h"

namespace twinray::stress {

std::string_view to_string(Status s) {
  switch (s) {
    case Status::Pass: return "pass";
    case Status::Fail: return "FAIL";
    case Status::Skip: return "skip";
  }
  return "?";
}

const std::vector<StressCase>& all_cases() {
  static const std::vector<StressCase> cases = [] {
    std::vector<StressCase> c;
    add_geometry_cases(c);
    add_grazing_slivers_case(c);
    add_robustness_cases(c);
    add_scale_cases(c);
    add_extreme_scale_case(c);
    add_light_transport_cases(c);
    return c;
  }();
  return cases;
}

const StressCase* find_case(std::string_view name) {
  for (const StressCase& c : all_cases())
    if (c.name == name) return &c;
  return nullptr;
}

}  // namespace twinray::stress
