#include "harness/grade/grade_run.h"

#include "core/scene/shared_data.h"
#include "core/util/fp_mode.h"
#include "core/util/input_error.h"
#include "harness/grade/checks.h"
#include "harness/grade/failed_builds.h"
#include "harness/grade/grade_scene.h"
#include "harness/grade/plugin_launcher.h"
#include "harness/grade/suite.h"
#include "core/util/text_safety.h"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

namespace twinray::grade {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

bool claims(const BackendTraits& traits, Category category) {
  if (category == Category::Watertight) return traits.watertight;
  if (category == Category::Ties) return traits.honours_ties;
  return true;
}

// Every built-in backend a check of this category uses on its scene.
void prepare_references(CheckContext& ctx) {
  ctx.scene.reference("embree");  // rays that start on surfaces come from its first hits
  ctx.scene.reference(ctx.reference_name());
  if (ctx.spec.category == Category::Performance) ctx.scene.reference("embree-fast");
  if (ctx.spec.category == Category::Performance || ctx.spec.category == Category::TreeQuality ||
      ctx.spec.category == Category::Complexity)
    ctx.scene.reference("bvh");
}

using Clock = std::chrono::steady_clock;

Clock::time_point after(Clock::time_point start, double seconds) {
  return start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

std::string budget_words(double budget) {
  return fmt::format("the suite's time_budget of {:g} s ran out; --time-budget changes it", budget);
}

// A plugin instance of the check did not end cleanly (checks.h, PluginInstance): a thread of the plugin crashed
// after the last answer, or destroy(), an exit handler or a static destructor crashed or hung. The answers are
// judged all the same; a check they pass takes the teardown's outcome (crash, timeout), one they fail stays
// failed. Either way the detail says it and figure `teardown` holds it; no single ray replays it.
void add_teardown_failure(const CheckContext& ctx, CheckResult& r) {
  const FailureReport f = classify_failure(ctx.teardown, ctx.spec.ray_time_limit_seconds);
  const std::string what = "at the end of the check (after its last answer: destroy, exit handlers, the plugin's "
                           "threads) " + f.detail;
  if (r.outcome == Outcome::Pass) {
    r.outcome = f.outcome;
    r.detail += ", but " + what;
    r.reproduce = ctx.grade_command();
  } else {
    r.detail += "; also " + what;
  }
  r.figures["teardown"] = {{"outcome", to_string(f.outcome)}, {"detail", one_line(f.detail)}};
  if (!f.output.empty() && !r.figures.contains("plugin_output")) r.figures["plugin_output"] = f.output;
}

// Runs one check in a fresh plugin worker and fills its outcome, detail, reproduce line, figures and image.
// `run_end` is when the run's time budget runs out, if it has one.
void execute(CheckContext& ctx, const std::filesystem::path& image_dir, CheckResult& r, std::vector<PendingImage>& images,
             std::optional<Clock::time_point> run_end, double budget) {
  // The references are built before the check's clock starts: its time limit is the plugin's.
  prepare_references(ctx);
  ctx.deadline = after(Clock::now(), ctx.spec.time_limit_seconds);
  if (run_end && *run_end < ctx.deadline) {
    ctx.deadline = *run_end;
    ctx.own_deadline = false;
  }
  try {
    CheckVerdict v = run_check(ctx);
    r.outcome = v.passed ? Outcome::Pass : Outcome::Fail;
    if (!v.scored) r.max_points = 0.0;
    r.detail = std::move(v.detail);
    r.reproduce = v.passed ? "" : std::move(v.reproduce);
    if (v.image) {
      const std::filesystem::path png = image_dir / (ctx.spec.name + ".png");
      r.image = png.string();
      images.push_back({png, std::move(*v.image)});
    }
    r.figures = std::move(v.figures);
    if (ctx.teardown) add_teardown_failure(ctx, r);
    r.detail = one_line(r.detail);  // a detail may quote the plugin's own words (its hit's ids, its message)
  } catch (const InputError&) {
    throw;
  } catch (const std::logic_error&) {
    throw;  // a bad --check name or a grader bug is never the plugin's fault
  } catch (const RecalledBuildFailure& recalled) {
    r.outcome = recalled.failed.failure.outcome;
    r.detail = one_line(FailedBuilds::recalled_detail(recalled.failed));
    r.reproduce = ctx.grade_command();
    r.figures = {{"same_build_as", recalled.failed.check}};
  } catch (...) {
    const FailureReport f = classify_failure(std::current_exception(), ctx.spec.ray_time_limit_seconds,
                                             ctx.own_deadline ? std::string(kCheckDeadline) : budget_words(budget));
    r.outcome = f.outcome;
    r.detail = one_line(f.detail);  // the plugin's build error message or exception text, as one safe line
    // One ray replays a crash or hang only when it happened to that ray alone: under the thread-safety check's
    // concurrent calls, a crash is the race's, and tracing the ray it hit answers normally.
    // Nor does it replay one of a batch call (`twinray trace` asks intersect1 and occluded1; the failure names
    // the call's first ray): the check reproduces it.
    const bool concurrent = ctx.spec.category == Category::ThreadSafety || ctx.spec.category == Category::BatchCalls;
    r.reproduce = f.ray && !concurrent ? ctx.trace_command(*f.ray) : ctx.grade_command();
    // A crash on a ray that, traced alone, is answered normally needs the calls before it (memory that ran out
    // over many calls, state kept between them): the check reproduces it, that ray does not.
    if (f.outcome == Outcome::Crash && f.ray && !concurrent && ctx.answer_alone(*f.ray)) {
      r.detail = one_line(f.detail) + "; traced alone that ray is answered normally: the crash needs the calls before "
                                      "it, so the reproduce line reruns the check";
      r.reproduce = ctx.grade_command();
      r.figures["replays_alone"] = false;
    }
    if (!f.output.empty()) r.figures["plugin_output"] = f.output;
  }
}

std::vector<const CheckSpec*> selected_checks(const Suite& suite, const std::vector<std::string>& only) {
  std::vector<const CheckSpec*> checks;
  if (only.empty()) {
    for (const CheckSpec& c : suite.checks) checks.push_back(&c);
    return checks;
  }
  for (const std::string& name : only)
    if (suite.find_check(name) == nullptr)
      throw std::invalid_argument(fmt::format("no check '{}' in suite '{}'", name, suite.name));
  for (const CheckSpec& c : suite.checks)  // manifest order, whatever the order of --check
    if (std::find(only.begin(), only.end(), c.name) != only.end()) checks.push_back(&c);
  return checks;
}

}  // namespace

Scorecard run_grade(const GradeSettings& settings) {
  const auto start = Clock::now();
  const ScopedFlushDenormals ftz;  // the mode every command queries backends in (core/util/fp_mode.h)
  Suite suite = load_suite(settings.suite);
  if (settings.time_scale != 1.0) {
    for (CheckSpec& c : suite.checks) {
      c.time_limit_seconds *= settings.time_scale;
      c.ray_time_limit_seconds *= settings.time_scale;
    }
    if (suite.time_budget_seconds) *suite.time_budget_seconds *= settings.time_scale;
  }
  const std::vector<const CheckSpec*> checks = selected_checks(suite, settings.only);
  const PluginLauncher plugin(settings.plugin);
  const bool shared_data = find_shared_data(suite.dir).has_value();

  Scorecard card;
  card.plugin = plugin.path().string();
  card.plugin_name = one_line(plugin.name());
  card.claims = plugin.traits();
  card.intersect_batch = plugin.has_intersect_batch();
  card.occluded_batch = plugin.has_occluded_batch();
  card.suite = suite.name;
  card.suite_path = suite.manifest.string();
  card.time_scale = settings.time_scale;
  card.time_calibration = settings.time_calibration;
  const std::optional<double> flag_budget = settings.time_budget;
  if (flag_budget) {
    if (*flag_budget > 0.0) card.time_budget = *flag_budget;
  } else {
    card.time_budget = suite.time_budget_seconds;
  }
  // The budget counts from the first check: loading the suite and the plugin is not the plugin's time.
  std::optional<Clock::time_point> run_end;

  if (settings.on_start) settings.on_start(card, checks.size());
  if (card.time_budget) run_end = after(Clock::now(), *card.time_budget);
  FailedBuilds failed_builds;

  // Scenes are loaded on first use and dropped after their last check (a million-triangle scene and its
  // reference backends should not stay for the rest of the suite).
  std::map<std::string, std::size_t> last_use;
  for (std::size_t i = 0; i < checks.size(); ++i) {
    last_use[checks[i]->scene] = i;
    if (!checks[i]->second_scene.empty()) last_use[checks[i]->second_scene] = i;
  }
  std::map<std::string, std::unique_ptr<GradeScene>> scenes;
  std::map<std::string, const CheckResult*> done;  // by name; points into card.checks (reserved below)
  card.checks.reserve(checks.size());
  const CheckEnvironment env{suite, plugin, settings.twinray, !settings.image_dir.empty(), settings.time_scale};

  for (std::size_t i = 0; i < checks.size(); ++i) {
    const CheckSpec& spec = *checks[i];
    const SuiteScene& scene_spec = suite.scenes.at(spec.scene);
    const bool second_needs_shared_data =
        !spec.second_scene.empty() && suite.scenes.at(spec.second_scene).needs_shared_data;
    CheckResult r;
    r.name = spec.name;
    r.category = spec.category;
    r.visibility = spec.visibility;
    r.description = spec.description;
    const bool claimed = claims(plugin.traits(), spec.category);
    r.required = spec.requirement == Requirement::Required || (spec.requirement == Requirement::IfClaimed && claimed);
    r.max_points = spec.requirement == Requirement::IfClaimed && !claimed ? 0.0 : spec.points;
    const auto check_start = Clock::now();

    // Prerequisites that ran and did not pass. One skipped for want of the shared data folder makes this
    // check uncounted too: its points must not depend on the machine.
    std::string unmet;
    bool unmet_uncounted = false;
    for (const std::string& need : spec.needs) {
      const auto it = done.find(need);
      if (it == done.end() || it->second->outcome == Outcome::Pass) continue;
      unmet += (unmet.empty() ? "" : ", ") + need + " (" + std::string(to_string(it->second->outcome)) + ")";
      unmet_uncounted = unmet_uncounted || (it->second->outcome == Outcome::Skipped && it->second->max_points == 0.0);
    }
    if (spec.category == Category::BatchCalls && !plugin.has_intersect_batch() && !plugin.has_occluded_batch()) {
      // The batch functions are optional: without them there is nothing to judge, and nothing to lose.
      r.outcome = Outcome::Skipped;
      r.max_points = 0.0;
      r.detail = "not applicable: the plugin has no intersect_batch or occluded_batch (optional; twinray calls "
                 "intersect1 and occluded1 instead, which the other checks judge); not counted";
      r.figures = {{"applicable", false}};
    } else if ((scene_spec.needs_shared_data || second_needs_shared_data) && !shared_data) {
      r.outcome = Outcome::Skipped;
      r.max_points = 0.0;
      r.detail = fmt::format("scene '{}' needs the shared data folder (set TWINRAY_SHARED); not counted",
                             scene_spec.needs_shared_data ? spec.scene : spec.second_scene);
    } else if (!unmet.empty()) {
      r.outcome = Outcome::Skipped;
      r.detail = "needs " + unmet + " to pass first";
      if (unmet_uncounted) r.max_points = 0.0;
    } else if (run_end && Clock::now() >= *run_end) {
      r.outcome = Outcome::Timeout;
      r.detail = "not run: " + budget_words(*card.time_budget);
      r.reproduce = grade_command(env, spec);
      r.figures = {{"time_budget_seconds", *card.time_budget}};
    } else {
      std::unique_ptr<GradeScene>& scene = scenes[spec.scene];
      if (!scene) scene = std::make_unique<GradeScene>(scene_spec, suite);
      CheckContext ctx{spec, *scene, env, {}, &failed_builds};
      if (!spec.second_scene.empty()) {
        std::unique_ptr<GradeScene>& second = scenes[spec.second_scene];
        if (!second) second = std::make_unique<GradeScene>(suite.scenes.at(spec.second_scene), suite);
        ctx.second_scene = second.get();
      }
      execute(ctx, settings.image_dir, r, card.images, run_end, card.time_budget.value_or(0.0));
      if (!r.required && r.failed() && spec.requirement == Requirement::IfClaimed)
        r.detail += " (not claimed by the plugin: reported, not required)";
    }
    r.points = r.outcome == Outcome::Pass ? r.max_points : 0.0;
    r.seconds = seconds_since(check_start);
    if (last_use[spec.scene] == i) scenes.erase(spec.scene);
    if (!spec.second_scene.empty() && last_use[spec.second_scene] == i) scenes.erase(spec.second_scene);
    if (spec.category == Category::Performance || spec.category == Category::TreeQuality ||
        spec.category == Category::Complexity)
      card.performance[spec.name] = r.figures;
    card.checks.push_back(std::move(r));
    done[spec.name] = &card.checks.back();
    if (settings.on_check) settings.on_check(card.checks.back(), i + 1, checks.size());
  }
  card.seconds = seconds_since(start);
  return card;
}

}  // namespace twinray::grade
