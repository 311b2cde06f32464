#pragma once
// A grading suite: a folder with a manifest (manifest.json) that lists scenes and checks, each check with its
// category, points, requirement and visibility. docs/grading.md specifies the format; load_suite validates
// all of it (unknown keys, wrong types, a check naming a scene or prerequisite that does not exist) and
// reports errors as InputError at the JSON pointer of the offending value.
//
// Bundled suites live in the repository's suites/ folder (`default`, `quick`); find_bundled_suite locates it
// from the running executable (see suite.cpp for why not compiled in).

#include "harness/crosscheck/ray_kinds.h"
#include "harness/grade/vocabulary.h"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace twinray::grade {

inline constexpr const char* kManifestName = "manifest.json";

struct SuiteScene {
  std::string id;               // the key in "scenes"
  std::string name;             // as written: a path relative to the suite folder, $TWINRAY_SHARED/..., procedural:...
  bool needs_shared_data = false;
};

// Pass criteria of the measuring categories; unset means "reported only".
struct Thresholds {
  // performance: plugin rays per second divided by bvh's / embree-fast's on the same rays, one thread.
  std::optional<double> min_speed_vs_bvh;
  std::optional<double> min_speed_vs_embree_fast;
  std::optional<double> max_build_seconds;
  // tree-quality: the plugin's reported SAH cost over the reference tree's (docs/plugin-abi.md's cost
  // model), and nodes / primitives per ray over bvh's.
  std::optional<double> max_sah_ratio;
  std::optional<double> max_nodes_per_ray_ratio;
  std::optional<double> max_primitives_per_ray_ratio;
  // complexity: the largest growth exponent allowed, log(time per ray on the scaled scene / on the scene) over
  // log(their primitive counts' ratio); 0.7 when absent (check_complexity.cpp says why).
  std::optional<double> max_growth_exponent;

  bool any() const {
    return min_speed_vs_bvh || min_speed_vs_embree_fast || max_build_seconds || max_sah_ratio ||
           max_nodes_per_ray_ratio || max_primitives_per_ray_ratio || max_growth_exponent;
  }
};

enum class Reference { Embree, Brute };

struct CheckSpec {
  std::string name;
  Category category = Category::ClosestHit;
  std::string scene;  // SuiteScene::id
  // closest-hit, "second_scene": a second instance of the plugin, in the same worker process as the one the
  // check queries, is built on this scene after the check's own build and before any query (the two-instances
  // check: instances in one process must be independent). Empty: one instance.
  std::string second_scene;
  double points = 0.0;
  Requirement requirement = Requirement::Required;
  Visibility visibility = Visibility::Visible;
  double time_limit_seconds = 60.0;
  double ray_time_limit_seconds = 2.0;  // one ray (one call into the plugin): what finds an endless loop fast
  std::size_t memory_limit_bytes = 0;
  std::uint64_t seed = 1;
  std::vector<std::string> needs;  // earlier checks that must pass first
  std::string description;

  std::vector<crosscheck::RayKind> rays;  // the ray kinds shot (category defaults when absent)
  std::size_t count = 0;                  // rays (per kind); category default when 0
  Reference reference = Reference::Embree;
  bool image = false;                      // closest-hit with camera rays: write the disagreement PNG
  int threads = 8;                         // thread-safety
  int repeat = 2;                          // thread-safety: at least this many rounds...
  double min_seconds = 1.0;                // ...and more until this much concurrent work is done
  std::optional<glm::vec3> origin;         // watertight: the interior point rays start from; deep-tree: the point
                                           // the scene nests around (default the origin of coordinates)
  Thresholds thresholds;
};

struct Suite {
  std::string name;
  std::string description;
  std::filesystem::path dir;       // absolute
  std::filesystem::path manifest;  // absolute
  bool bundled = false;            // found by name among the bundled suites
  std::map<std::string, SuiteScene> scenes;
  std::vector<CheckSpec> checks;
  // "time_budget": wall-clock seconds for the whole run; once spent, the checks still to run are reported
  // `timeout` without running (a check under way is cut at it). None when absent.
  std::optional<double> time_budget_seconds;

  const CheckSpec* find_check(std::string_view name) const;
};

// `name_or_dir`: a folder (or its manifest.json) when it names one or contains a '/', otherwise the name of a
// bundled suite. Throws InputError.
Suite load_suite(const std::string& name_or_dir);

// Reads and validates one manifest. Throws InputError at the JSON pointer of the first problem.
Suite parse_suite_manifest(const std::filesystem::path& manifest);

// The folder of the bundled suites (…/suites), or nothing when it cannot be found.
std::optional<std::filesystem::path> bundled_suites_dir();
std::vector<std::string> bundled_suite_names();

}  // namespace twinray::grade
