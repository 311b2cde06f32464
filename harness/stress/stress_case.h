#pragma once
// The `twinray stress` catalogue: named cases where floating point gets hard, each run once per backend.
//
// A case builds its own small scene, runs it through one backend and returns an Outcome: pass or fail, the
// figures behind the verdict, and whether the backend *claims* to handle the case. Claims come from
// BackendTraits (watertight, honours_ties, counts_traversal) and from the backend's documented contract:
// embree-fast is never required to pass (it trades robustness for speed), so its failures are reported
// but do not fail the run. docs/stress.md describes every case and where it comes from.

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace twinray::stress {

// How much work a case does. 1 is the command's default (the whole catalogue in about a minute on two
// cores); tests use a fraction. Cases scale ray and sample counts with it, never their geometry, so the
// hard configurations are exercised at every effort.
struct StressOptions {
  double effort = 1.0;
};

enum class Status { Pass, Fail, Skip };
std::string_view to_string(Status s);

struct Outcome {
  Status status = Status::Pass;
  bool required = true;  // false: reported, but a failure does not fail the run
  std::string figures;   // one line of the numbers behind the verdict
  std::string note;      // why it failed, was skipped or is not required (empty when obvious)
  nlohmann::json json = nlohmann::json::object();

  bool counts_as_failure() const { return status == Status::Fail && required; }
};

struct StressCase {
  std::string name;
  std::string family;   // geometry, robustness, scale, light-transport
  std::string summary;  // one line: what it checks
  std::function<Outcome(const std::string& backend, const StressOptions& options)> run;
};

// Every case in catalogue order.
const std::vector<StressCase>& all_cases();
// nullptr for an unknown name.
const StressCase* find_case(std::string_view name);

// The catalogue families, each in its own file.
void add_geometry_cases(std::vector<StressCase>& cases);
void add_grazing_slivers_case(std::vector<StressCase>& cases);  // geometry family, in its own file
void add_robustness_cases(std::vector<StressCase>& cases);
void add_scale_cases(std::vector<StressCase>& cases);
void add_extreme_scale_case(std::vector<StressCase>& cases);  // scale family, in its own file
void add_light_transport_cases(std::vector<StressCase>& cases);

}  // namespace twinray::stress
