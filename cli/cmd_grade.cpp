// twinray grade: a plugin, a suite, a scorecard (terminal, JSON, Gradescope, JUnit, disagreement images).

#include "cli/commands.h"
#include "core/image/image_io.h"
#include "core/util/atomic_file.h"
#include "core/util/input_error.h"
#include "core/util/progress.h"
#include "harness/grade/grade_run.h"
#include "harness/grade/reports.h"
#include "harness/grade/suite.h"
#include "harness/grade/time_calibration.h"

#include <fmt/core.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>

namespace twinray::cli {

namespace {

struct GradeOptions {
  std::string plugin;
  std::string suite = "default";
  std::vector<std::string> checks;
  std::string json;
  std::string gradescope;
  std::string junit;
  std::string out;
  std::optional<double> time_budget;
  std::string time_scale = "1";  // a factor, or "auto"
  bool list = false;
};

// An output file's folder must exist before the run starts, so that a typo is bad input up front rather than
// a failure after minutes of grading (and no output is written unless all of them can be).
void require_output_folder(const std::string& file, const char* flag) {
  if (file.empty()) return;
  const std::filesystem::path parent = std::filesystem::absolute(file).parent_path();
  std::error_code ec;
  if (!std::filesystem::is_directory(parent, ec))
    throw InputError(file, "", fmt::format("{}: the folder {} does not exist", flag, parent.string()));
}

// A number as C's strtod reads it, with nothing after it; nullopt otherwise.
std::optional<double> parse_factor(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) return std::nullopt;
  return value;
}

std::string running_executable() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("twinray") : exe.string();
}

int list_suite(const std::string& name) {
  const grade::Suite suite = grade::load_suite(name);
  fmt::print("suite {} ({}){}\n", suite.name, suite.manifest.string(), suite.description.empty() ? "" : ": " + suite.description);
  for (const grade::CheckSpec& c : suite.checks)
    fmt::print("  {:<30} {:<13} {:>5} points  scene {}{}\n", c.name, grade::to_string(c.category),
               grade::format_points(c.points), c.scene, c.description.empty() ? "" : "  " + c.description);
  return kExitOk;
}

int run_grade_command(const GradeOptions& opt) {
  if (opt.list) return list_suite(opt.suite);
  if (opt.plugin.empty()) return report_bad_input("grade", "give the plugin to grade (a shared library, see docs/grading.md)");
  require_output_folder(opt.json, "--json");
  require_output_folder(opt.gradescope, "--gradescope");
  require_output_folder(opt.junit, "--junit");

  grade::GradeSettings settings;
  settings.plugin = opt.plugin;
  settings.suite = opt.suite;
  settings.only = opt.checks;
  settings.image_dir = opt.out;
  settings.twinray = running_executable();
  if (opt.time_budget) {
    if (!(*opt.time_budget >= 0.0) || *opt.time_budget > 86400.0)
      return report_bad_input("grade", "--time-budget is a number of seconds from 0 (no budget) to 86400");
    settings.time_budget = opt.time_budget;
  }
  if (opt.time_scale == "auto") {
    settings.time_calibration = grade::calibrate_time_scale();
    settings.time_scale = settings.time_calibration->scale;
  } else {
    const std::optional<double> f = parse_factor(opt.time_scale);
    if (!f || !(*f > 0.0) || *f > 100.0)
      return report_bad_input("grade", "--time-scale is a factor greater than 0 and at most 100, or auto");
    settings.time_scale = *f;
  }

  // The header once the suite and plugin are loaded; check lines on stdout as they finish, the progress line
  // (stderr, terminals only) cleared before each.
  std::optional<Progress> progress;
  settings.on_start = [&](const grade::Scorecard& card, std::size_t total) {
    fmt::print("{}", grade::terminal_header(card, total));
    std::fflush(stdout);
    progress.emplace("grade", total);
  };
  settings.on_check = [&](const grade::CheckResult& result, std::size_t, std::size_t) {
    if (progress->enabled()) fmt::print(stderr, "\r\033[K");
    fmt::print("{}", grade::terminal_check_line(result));
    std::fflush(stdout);
    progress->advance();
  };

  grade::Scorecard card;
  try {
    card = grade::run_grade(settings);
  } catch (const std::invalid_argument& e) {
    return report_bad_input("grade", e.what());
  }
  if (progress) progress->finish();
  fmt::print("{}", grade::terminal_totals(card));

  if (!card.images.empty()) std::filesystem::create_directories(opt.out);
  for (const grade::PendingImage& image : card.images) write_png(image.path, image.image);
  if (!opt.json.empty()) write_file_atomically(opt.json, grade::json_file_text(grade::scorecard_json(card)));
  if (!opt.gradescope.empty()) write_file_atomically(opt.gradescope, grade::json_file_text(grade::gradescope_json(card)));
  if (!opt.junit.empty()) write_file_atomically(opt.junit, grade::junit_xml(card));
  return card.passed() ? kExitOk : kExitCheckFailed;
}

}  // namespace

void add_grade_command(CLI::App& app, CommandRunner& run) {
  auto opt = std::make_shared<GradeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "grade",
      "Grade a BVH plugin with a suite of checks (build, closest-hit, any-hit, ray-interval, axis-aligned,\n"
      "watertight, spheres, ties, deep-tree, thread-safety, determinism, performance, tree-quality,\n"
      "batch-calls, complexity); each check runs the plugin in a fresh worker process with a time and memory limit.\n"
      "Prints one line per check and a total; every failure comes with a command that reproduces it.\n"
      "Exit code: 0 every required check passed, 1 a check failed (crash and timeout included), 2 bad input.");
  cmd->add_option("plugin", opt->plugin, "The plugin: a shared library exporting twinray_plugin_entry (docs/plugin-abi.md)");
  cmd->add_option("--suite", opt->suite,
                  "A bundled suite (default, quick) or a folder with a manifest.json (docs/grading.md)")
      ->capture_default_str();
  cmd->add_option("--check", opt->checks, "Run only this check (repeatable); its prerequisites are then not required");
  cmd->add_option("--json", opt->json, "Write the scorecard as JSON");
  cmd->add_option("--gradescope", opt->gradescope, "Write Gradescope's results.json");
  cmd->add_option("--junit", opt->junit, "Write JUnit XML");
  cmd->add_option("--out", opt->out, "Write a PNG per camera-ray check with an image, marking wrong pixels in red");
  cmd->add_option("--time-budget", opt->time_budget,
                  "Seconds for the whole run, overriding the suite's time_budget (0: none); once spent, the checks\n"
                  "still to run are reported timeout without running");
  cmd->add_option("--time-scale", opt->time_scale,
                  "Multiply every check's time limits and the suite's time_budget by this factor (0 < F <= 100), for a\n"
                  "slower or busier grading machine; reproduce lines repeat it. auto: time a fixed workload of twinray's\n"
                  "bvh backend (about a second) and take the factor from a coarse ladder, never below 1 (docs/grading.md)")
      ->capture_default_str();
  cmd->add_flag("--list", opt->list, "List the suite's checks and exit");
  cmd->callback([opt, &run] { run = [opt] { return run_grade_command(*opt); }; });
}

}  // namespace twinray::cli
