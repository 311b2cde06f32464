#include "harness/grade/suite.h"

#include "core/scene/input_file.h"
#include "core/scene/json_reader.h"
#include "core/util/input_error.h"
#include "harness/scenes/named_scene.h"

#include <fmt/core.h>

#include <algorithm>
#include <set>
#include <system_error>
#include <unistd.h>

namespace twinray::grade {

namespace {

// Defaults every check inherits unless its manifest or the "defaults" object says otherwise.
constexpr double kDefaultTimeLimit = 60.0;                               // seconds per check, build included
constexpr std::size_t kDefaultMemoryLimitMiB = 4096;                     // the plugin's worker process
constexpr double kMaxTimeLimit = 3600.0;
constexpr double kMaxTimeBudget = 86400.0;  // a day: a budget is a guard against hangs, not a schedule
// One ray is one call into the plugin. Two seconds is a thousand times what a brute-force loop over a
// million triangles takes, so only a plugin stuck in a loop reaches it, and it is found in seconds rather
// than at the end of the check's whole budget.
constexpr double kDefaultRayTimeLimit = 2.0;
constexpr std::int64_t kMaxMemoryLimitMiB = 1 << 20;                     // 1 TiB
constexpr std::int64_t kMaxRays = 10'000'000;                            // per kind, like crosscheck --rays

struct Defaults {
  double time_limit = kDefaultTimeLimit;
  double ray_time_limit = kDefaultRayTimeLimit;
  std::size_t memory_limit_bytes = kDefaultMemoryLimitMiB << 20;
  Visibility visibility = Visibility::Visible;
  std::uint64_t seed = 1;
};

bool valid_check_name(const std::string& name) {
  if (name.empty() || name.size() > 80) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_' || c == '.';
  });
}

double time_limit_of(const JsonNode& node) {
  const double t = node.as_double();
  if (!(t > 0.0) || t > kMaxTimeLimit) node.fail(fmt::format("a time limit is in (0, {}] seconds", kMaxTimeLimit));
  return t;
}

std::size_t memory_limit_of(const JsonNode& node) {
  return static_cast<std::size_t>(node.as_integer(64, kMaxMemoryLimitMiB)) << 20;
}

Visibility visibility_of(const JsonNode& node) {
  const std::optional<Visibility> v = parse_visibility(node.as_string());
  if (!v) node.fail("visibility is one of visible, hidden, after_due_date, after_published (Gradescope's values)");
  return *v;
}

Defaults parse_defaults(const JsonNode& node) {
  node.expect_object({"time_limit", "ray_time_limit", "memory_limit_mib", "visibility", "seed"});
  Defaults d;
  if (auto n = node.optional_member("time_limit")) d.time_limit = time_limit_of(*n);
  if (auto n = node.optional_member("ray_time_limit")) d.ray_time_limit = time_limit_of(*n);
  if (auto n = node.optional_member("memory_limit_mib")) d.memory_limit_bytes = memory_limit_of(*n);
  if (auto n = node.optional_member("visibility")) d.visibility = visibility_of(*n);
  if (auto n = node.optional_member("seed")) d.seed = n->as_unsigned();
  return d;
}

SuiteScene parse_scene(const std::string& id, const JsonNode& node) {
  SuiteScene s;
  s.id = id;
  if (node.json().is_string()) {
    s.name = node.as_string();
  } else {
    node.expect_object({"path", "shared_data"});
    s.name = node.member("path").as_string();
    if (auto n = node.optional_member("shared_data")) {
      if (!n->json().is_boolean()) n->fail("expected true or false");
      s.needs_shared_data = n->json().get<bool>();
    }
  }
  if (s.name.empty()) node.fail("a scene is a file path (relative to the suite folder), $TWINRAY_SHARED/... or procedural:...");
  for (std::string_view prefix : {"$TWINRAY_SHARED/", "${TWINRAY_SHARED}/"})
    if (s.name.starts_with(prefix)) s.needs_shared_data = true;
  return s;
}

std::vector<crosscheck::RayKind> ray_kinds_of(const JsonNode& node) {
  std::vector<std::string> names;
  if (node.json().is_string()) {
    names.push_back(node.as_string());
  } else {
    const std::size_t n = node.expect_array();
    if (n == 0) node.fail("list at least one ray kind");
    for (std::size_t i = 0; i < n; ++i) names.push_back(node.element(i).as_string());
  }
  std::vector<crosscheck::RayKind> kinds;
  for (const std::string& name : names) {
    const std::optional<crosscheck::RayKind> k = crosscheck::parse_ray_kind(name);
    if (!k) node.fail(fmt::format("unknown ray kind '{}' (choose from camera, uniform, diffuse, shadow)", name));
    if (std::find(kinds.begin(), kinds.end(), *k) != kinds.end()) node.fail(fmt::format("ray kind '{}' listed twice", name));
    kinds.push_back(*k);
  }
  return kinds;
}

// Which keys each category takes beyond the common ones.
std::vector<std::string_view> parameters_of(Category c) {
  switch (c) {
    case Category::Build: return {"count", "reference"};
    case Category::ClosestHit: return {"rays", "count", "reference", "image", "second_scene", "origin"};
    case Category::AnyHit: return {"rays", "count", "reference"};
    case Category::RayInterval: return {"rays", "count", "reference"};
    case Category::AxisAligned: return {"count", "reference"};
    case Category::Watertight: return {"count", "origin"};
    case Category::Spheres: return {"count", "reference"};
    case Category::Ties: return {"count"};
    case Category::ThreadSafety: return {"rays", "count", "threads", "repeat", "min_seconds"};
    case Category::Determinism: return {"rays", "count"};
    case Category::Performance: return {"rays", "count", "thresholds"};
    case Category::TreeQuality: return {"rays", "count", "thresholds"};
    case Category::DeepTree: return {"count", "reference", "origin"};
    case Category::BatchCalls: return {"rays", "count", "reference"};
    case Category::Complexity: return {"rays", "count", "second_scene", "thresholds"};
  }
  return {};
}

Thresholds thresholds_of(const JsonNode& node, Category category) {
  Thresholds t;
  const auto ratio = [](const JsonNode& n) {
    const double v = n.as_double();
    if (!(v > 0.0)) n.fail("a threshold is a positive number");
    return v;
  };
  if (category == Category::Performance) {
    node.expect_object({"min_speed_vs_bvh", "min_speed_vs_embree_fast", "max_build_seconds"});
    if (auto n = node.optional_member("min_speed_vs_bvh")) t.min_speed_vs_bvh = ratio(*n);
    if (auto n = node.optional_member("min_speed_vs_embree_fast")) t.min_speed_vs_embree_fast = ratio(*n);
    if (auto n = node.optional_member("max_build_seconds")) t.max_build_seconds = ratio(*n);
  } else if (category == Category::Complexity) {
    node.expect_object({"max_growth_exponent"});
    if (auto n = node.optional_member("max_growth_exponent")) t.max_growth_exponent = ratio(*n);
  } else {
    node.expect_object({"max_sah_ratio", "max_nodes_per_ray_ratio", "max_primitives_per_ray_ratio"});
    if (auto n = node.optional_member("max_sah_ratio")) t.max_sah_ratio = ratio(*n);
    if (auto n = node.optional_member("max_nodes_per_ray_ratio")) t.max_nodes_per_ray_ratio = ratio(*n);
    if (auto n = node.optional_member("max_primitives_per_ray_ratio")) t.max_primitives_per_ray_ratio = ratio(*n);
  }
  return t;
}

CheckSpec parse_check(const JsonNode& node, const Defaults& defaults, const Suite& suite,
                      const std::set<std::string>& earlier) {
  if (!node.is_object()) node.fail("a check is an object with at least name, category, scene and points");
  const JsonNode category_node = node.member("category");
  const std::optional<Category> category = parse_category(category_node.as_string());
  if (!category) {
    std::string all;
    for (Category c : kAllCategories) all += (all.empty() ? "" : ", ") + std::string(to_string(c));
    category_node.fail(fmt::format("unknown category (choose from {})", all));
  }
  std::vector<std::string_view> allowed = {"name",       "category",   "scene",          "points",
                                           "required",   "visibility", "time_limit",     "ray_time_limit",
                                           "memory_limit_mib", "seed", "needs",          "description"};
  for (std::string_view p : parameters_of(*category)) allowed.push_back(p);
  // expect_object takes an initializer list; check the keys here with the same message shape.
  for (const auto& [key, value] : node.json().items()) {
    if (key == "comment") continue;
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      std::string list;
      for (std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      node.member(key).fail(fmt::format("unknown key '{}' for a {} check (allowed: {})", key, to_string(*category), list));
    }
  }

  CheckSpec c;
  c.category = *category;
  const JsonNode name = node.member("name");
  c.name = name.as_string();
  if (!valid_check_name(c.name)) name.fail("a check name is 1 to 80 characters of a-z, 0-9, '-', '_' and '.'");
  if (earlier.count(c.name) != 0) name.fail(fmt::format("two checks are named '{}'", c.name));

  const JsonNode scene = node.member("scene");
  c.scene = scene.as_string();
  if (suite.scenes.count(c.scene) == 0) scene.fail(fmt::format("no scene '{}' in \"scenes\"", c.scene));

  const JsonNode points = node.member("points");
  c.points = points.as_double();
  if (!(c.points >= 0.0) || c.points > 1e6) points.fail("points are a number in [0, 1000000]");

  if (auto n = node.optional_member("required")) {
    if (n->json().is_boolean()) {
      c.requirement = n->json().get<bool>() ? Requirement::Required : Requirement::Optional;
    } else if (n->json().is_string() && n->json().get<std::string>() == "if-claimed") {
      if (c.category != Category::Watertight && c.category != Category::Ties)
        n->fail("\"if-claimed\" applies to watertight and ties checks (the properties a plugin claims with its flags)");
      c.requirement = Requirement::IfClaimed;
    } else {
      n->fail("required is true, false or \"if-claimed\"");
    }
  }
  c.visibility = defaults.visibility;
  if (auto n = node.optional_member("visibility")) c.visibility = visibility_of(*n);
  c.time_limit_seconds = defaults.time_limit;
  if (auto n = node.optional_member("time_limit")) c.time_limit_seconds = time_limit_of(*n);
  c.ray_time_limit_seconds = defaults.ray_time_limit;
  if (auto n = node.optional_member("ray_time_limit")) c.ray_time_limit_seconds = time_limit_of(*n);
  c.memory_limit_bytes = defaults.memory_limit_bytes;
  if (auto n = node.optional_member("memory_limit_mib")) c.memory_limit_bytes = memory_limit_of(*n);
  c.seed = defaults.seed;
  if (auto n = node.optional_member("seed")) c.seed = n->as_unsigned();
  if (auto n = node.optional_member("description")) c.description = n->as_string();
  if (auto n = node.optional_member("needs")) {
    const std::size_t count = n->expect_array();
    for (std::size_t i = 0; i < count; ++i) {
      const JsonNode e = n->element(i);
      const std::string need = e.as_string();
      if (earlier.count(need) == 0) e.fail(fmt::format("'{}' is not a check listed before this one", need));
      c.needs.push_back(need);
    }
  }

  if (auto n = node.optional_member("rays")) c.rays = ray_kinds_of(*n);
  if (auto n = node.optional_member("count")) c.count = static_cast<std::size_t>(n->as_integer(1, kMaxRays));
  if (auto n = node.optional_member("reference")) {
    const std::string r = n->as_string();
    if (r == "embree") c.reference = Reference::Embree;
    else if (r == "brute") c.reference = Reference::Brute;
    else n->fail("reference is \"embree\" (robust Embree, any scene) or \"brute\" (every primitive, small scenes)");
  }
  if (auto n = node.optional_member("image")) {
    if (!n->json().is_boolean()) n->fail("expected true or false");
    c.image = n->json().get<bool>();
    if (c.image && std::find(c.rays.begin(), c.rays.end(), crosscheck::RayKind::Camera) == c.rays.end())
      n->fail("an image needs camera rays (\"rays\": \"camera\")");
  }
  if (auto n = node.optional_member("second_scene")) {
    c.second_scene = n->as_string();
    if (suite.scenes.count(c.second_scene) == 0) n->fail(fmt::format("no scene '{}' in \"scenes\"", c.second_scene));
  }
  if (c.category == Category::Complexity && c.second_scene.empty())
    node.fail("a complexity check needs \"second_scene\": the same kind of scene with several (the bundled suites: 16) times the primitives");
  if (auto n = node.optional_member("threads")) c.threads = static_cast<int>(n->as_integer(2, 64));
  if (auto n = node.optional_member("repeat")) c.repeat = static_cast<int>(n->as_integer(1, 100));
  if (auto n = node.optional_member("min_seconds")) {
    c.min_seconds = n->as_double();
    if (!(c.min_seconds >= 0.0) || c.min_seconds > kMaxTimeLimit) n->fail("min_seconds is a number of seconds, at least 0");
  }
  if (auto n = node.optional_member("origin")) c.origin = n->as_vec3();
  if (auto n = node.optional_member("thresholds")) c.thresholds = thresholds_of(*n, c.category);
  if (c.category == Category::ClosestHit)
    for (crosscheck::RayKind k : c.rays)
      if (k == crosscheck::RayKind::Shadow)
        node.member("rays").fail("shadow rays are any-hit queries: use them in an any-hit check");
  return c;
}

std::filesystem::path executable_dir() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path() : exe.parent_path();
}

// A folder named suites with at least one suite in it.
bool is_suites_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) return false;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec))
    if (std::filesystem::is_regular_file(entry.path() / kManifestName, ec)) return true;
  return false;
}

}  // namespace

const CheckSpec* Suite::find_check(std::string_view check_name) const {
  for (const CheckSpec& c : checks)
    if (c.name == check_name) return &c;
  return nullptr;
}

Suite parse_suite_manifest(const std::filesystem::path& manifest_path) {
  std::error_code ec;
  const std::filesystem::path manifest = std::filesystem::absolute(manifest_path, ec);
  const Json doc = parse_json_text(read_input_file(manifest), manifest);
  const JsonNode root(doc, "", manifest);
  root.expect_object({"suite", "description", "defaults", "time_budget", "scenes", "checks"});

  Suite suite;
  suite.manifest = manifest;
  suite.dir = manifest.parent_path();
  suite.name = root.member("suite").as_string();
  if (!valid_check_name(suite.name))
    root.member("suite").fail("a suite name is 1 to 80 characters of a-z, 0-9, '-', '_' and '.'");
  if (auto n = root.optional_member("description")) suite.description = n->as_string();
  Defaults defaults;
  if (auto n = root.optional_member("defaults")) defaults = parse_defaults(*n);
  if (auto n = root.optional_member("time_budget")) {
    const double t = n->as_double();
    if (!(t > 0.0) || t > kMaxTimeBudget) n->fail(fmt::format("a time budget is in (0, {}] seconds", kMaxTimeBudget));
    suite.time_budget_seconds = t;
  }

  const JsonNode scenes = root.member("scenes");
  if (!scenes.is_object()) scenes.fail("\"scenes\" is an object mapping a scene id to a scene");
  for (const auto& [id, value] : doc.at("scenes").items()) {
    if (id == "comment") continue;
    suite.scenes.emplace(id, parse_scene(id, scenes.member(id)));
  }

  const JsonNode checks = root.member("checks");
  const std::size_t n = checks.expect_array();
  if (n == 0) checks.fail("a suite has at least one check");
  std::set<std::string> earlier;
  for (std::size_t i = 0; i < n; ++i) {
    suite.checks.push_back(parse_check(checks.element(i), defaults, suite, earlier));
    earlier.insert(suite.checks.back().name);
  }
  return suite;
}

std::optional<std::filesystem::path> bundled_suites_dir() {
  // Suites are folders of data (manifests, and scene files they may bring along) that name the repository's
  // bundled scenes by relative path, so they are found as files rather than compiled in. Searched upward
  // from the executable (build/cli/twinray, build-asan/..., an install's bin/ with share/twinray/suites),
  // then in the source tree this binary was configured from, which covers a build folder outside it.
  std::vector<std::filesystem::path> candidates;
  for (std::filesystem::path dir = executable_dir(); !dir.empty(); dir = dir.parent_path()) {
    candidates.push_back(dir / "suites");
    candidates.push_back(dir / "share" / "twinray" / "suites");
    if (dir == dir.parent_path()) break;
  }
#ifdef TWINRAY_SOURCE_DIR
  candidates.push_back(std::filesystem::path(TWINRAY_SOURCE_DIR) / "suites");
#endif
  for (const std::filesystem::path& c : candidates)
    if (is_suites_dir(c)) return std::filesystem::weakly_canonical(c);
  return std::nullopt;
}

std::vector<std::string> bundled_suite_names() {
  std::vector<std::string> names;
  const std::optional<std::filesystem::path> dir = bundled_suites_dir();
  if (!dir) return names;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(*dir, ec))
    if (std::filesystem::is_regular_file(entry.path() / kManifestName, ec)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

Suite load_suite(const std::string& name_or_dir) {
  std::error_code ec;
  const std::filesystem::path given(name_or_dir);
  const bool looks_like_path = name_or_dir.find('/') != std::string::npos || std::filesystem::exists(given, ec);
  if (looks_like_path) {
    const std::filesystem::path manifest = std::filesystem::is_directory(given, ec) ? given / kManifestName : given;
    return parse_suite_manifest(manifest);
  }
  const std::optional<std::filesystem::path> dir = bundled_suites_dir();
  if (!dir)
    throw InputError(given, "",
                     "no suite folder of that name, and the bundled suites (suites/ of the twinray source tree) were "
                     "not found beside this executable");
  const std::filesystem::path manifest = *dir / name_or_dir / kManifestName;
  if (!std::filesystem::is_regular_file(manifest, ec)) {
    std::string names;
    for (const std::string& s : bundled_suite_names()) names += (names.empty() ? "" : ", ") + s;
    throw InputError(given, "", fmt::format("no such suite (bundled: {}; or give a folder with a {})", names, kManifestName));
  }
  Suite suite = parse_suite_manifest(manifest);
  suite.bundled = true;
  return suite;
}

}  // namespace twinray::grade
