#include "harness/grade/checks.h"

#include "backends/plugin/plugin_failure.h"
#include "harness/grade/answers.h"
#include "harness/grade/grade_rays.h"
#include "core/geometry/ray_text.h"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>

namespace twinray::grade {

void PluginInstance::end() {
  if (!backend_) return;
  try {
    backend_->shutdown();
  } catch (const PluginFailure&) {
    // Only a failure no call has thrown reaches here (shutdown's contract): a crash after the last answer or
    // in teardown. One that a call threw is the check's outcome already.
    if (!ctx_->teardown) ctx_->teardown = std::current_exception();
  } catch (...) {
    // Anything else at teardown is not the plugin's to answer for, and a destructor must not throw.
  }
  backend_.reset();
}

PluginInstance CheckContext::built_plugin(double* build_seconds) const {
  const bool first = builds++ == 0;
  if (first && failed_builds != nullptr)
    if (std::optional<FailedBuild> f = failed_builds->recall(spec)) throw RecalledBuildFailure(std::move(*f));
  std::unique_ptr<IsolatedPluginBackend> plugin = env.plugin.launch(limits());
  const auto start = std::chrono::steady_clock::now();
  const auto seconds = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  try {
    plugin->build(scene.geometry());
    if (second_scene != nullptr) {
      // The two-instances check: a second instance in the same worker, built on another scene; every later
      // call goes to the first again, whose answers must not have changed (docs/plugin-abi.md).
      plugin->use_instance(1);
      plugin->build(second_scene->geometry());
      plugin->use_instance(0);
    }
  } catch (...) {
    if (first && failed_builds != nullptr) failed_builds->remember(spec, std::current_exception(), seconds(), own_deadline);
    throw;
  }
  if (build_seconds != nullptr) *build_seconds = seconds();
  return PluginInstance(std::move(plugin), *this);
}

std::optional<CheckContext::AloneAnswer> CheckContext::answer_alone(const Ray& ray) const {
  const std::exception_ptr kept = teardown;  // the replay's own end is not the check's
  std::optional<AloneAnswer> answer;
  try {
    PluginInstance plugin = built_plugin();
    AloneAnswer a;
    (*plugin).intersect(ray, a.hit);
    a.occluded = (*plugin).occluded(ray);
    plugin.end();
    answer = a;
  } catch (const std::exception&) {
    // A crash, a timeout or a failed build of the replay: it proves nothing about the check's failure.
  }
  teardown = kept;
  return answer;
}

void CheckContext::confirm_replay(CheckVerdict& v, const Ray& ray, bool any_hit, const Hit& batch_hit,
                                  bool batch_occluded) const {
  if (second_scene != nullptr) {
    // `twinray trace` builds one instance: only the whole check builds the second one beside it.
    v.detail += fmt::format("; with a second instance of the plugin built on scene '{}' in the same process "
                            "(instances must be independent: no tree or other mutable state shared between them)",
                            spec.second_scene);
    v.reproduce = grade_command();
    return;
  }
  const std::optional<AloneAnswer> alone = answer_alone(ray);
  if (!alone) return;
  const bool same = any_hit ? alone->occluded == batch_occluded : same_bits(alone->hit, batch_hit);
  v.figures["replays_alone"] = same;
  if (same) return;
  v.detail += fmt::format(
      "; asked alone (as the reproduce line asks it) the plugin answers {} instead: its answers depend on the rays "
      "asked before (state kept between calls), so the reproduce line reruns the check",
      any_hit ? (alone->occluded ? "occluded" : "not occluded") : describe_hit(alone->hit));
  v.reproduce = grade_command();
}

std::string CheckContext::reference_name() const {
  // A ties check is refereed by brute, which honours the tie rule and so names the lowest-id copy.
  return spec.reference == Reference::Brute || spec.category == Category::Ties ? "brute" : "embree";
}

std::string shell_quote(const std::string& word) {
  const bool safe = !word.empty() && std::all_of(word.begin(), word.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
           std::string_view("-_./:,+=@%").find(c) != std::string_view::npos;
  });
  if (safe) return word;
  std::string quoted = "'";
  for (char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string CheckContext::trace_command(const Ray& ray) const {
  return fmt::format("{} trace {} --backends {} --ray '{}'", shell_quote(env.twinray), shell_quote(scene.trace_name()),
                     shell_quote("plugin:" + env.plugin.path().string() + "," + reference_name()), format_ray_hex(ray));
}

std::string CheckContext::grade_command() const { return grade::grade_command(env, spec); }

std::string grade_command(const CheckEnvironment& env, const CheckSpec& spec) {
  const std::string suite = env.suite.bundled ? env.suite.name : env.suite.dir.string();
  return fmt::format("{} grade {} --suite {} --check {}{}", shell_quote(env.twinray), shell_quote(env.plugin.path().string()),
                     shell_quote(suite), shell_quote(spec.name),
                     env.time_scale == 1.0 ? std::string() : fmt::format(" --time-scale {:g}", env.time_scale));
}

std::vector<Ray> CheckContext::rays_of_kinds(const std::vector<crosscheck::RayKind>& fallback, std::size_t count) const {
  const std::vector<crosscheck::RayKind>& kinds = spec.rays.empty() ? fallback : spec.rays;
  std::vector<Ray> rays;
  for (const crosscheck::RayKind k : kinds) {
    const std::vector<Ray> some = kind_rays(k, scene.scene(), scene.reference("embree"), count, spec.seed);
    rays.insert(rays.end(), some.begin(), some.end());
  }
  return rays;
}

CheckVerdict run_check(CheckContext& context) {
  switch (context.spec.category) {
    case Category::Build: return run_build_check(context);
    case Category::ClosestHit:
    case Category::AnyHit:
    case Category::RayInterval:
    case Category::AxisAligned:
    case Category::Spheres:
    case Category::Ties:
    case Category::DeepTree: return run_answer_check(context);
    case Category::Watertight: return run_watertight_check(context);
    case Category::ThreadSafety: return run_thread_safety_check(context);
    case Category::Determinism: return run_determinism_check(context);
    case Category::Performance: return run_performance_check(context);
    case Category::TreeQuality: return run_tree_quality_check(context);
    case Category::BatchCalls: return run_batch_check(context);
    case Category::Complexity: return run_complexity_check(context);
  }
  throw std::logic_error("unknown check category");
}

}  // namespace twinray::grade
