// twinray: one program, one subcommand per job. See docs/cli.md for the contract (flags, exit codes, JSON).

#include "backends/plugin/plugin_failure.h"
#include "cli/commands.h"
#include "core/util/input_error.h"
#include "core/util/text_safety.h"

#include <fmt/core.h>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  using namespace twinray::cli;
  CLI::App app{"twinray: a path tracer over interchangeable ray-intersection backends (bvh8, bvh, embree, embree-fast, brute)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "twinray 0.1.0");

  CommandRunner run;
  add_info_command(app, run);
  add_crosscheck_command(app, run);
  add_render_command(app, run);
  add_stress_command(app, run);
  add_converge_command(app, run);
  add_report_command(app, run);
  add_export_command(app, run);
  add_compare_command(app, run);
  add_trace_command(app, run);
  add_grade_command(app, run);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are "errors" with exit code 0 in CLI11.
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  }

  try {
    return run ? run() : kExitBadInput;
  } catch (const twinray::InputError& e) {
    fmt::print(stderr, "twinray: error: {}\n", e.what());
    return kExitBadInput;
  } catch (const twinray::PluginFailure& e) {
    // The plugin under test crashed, hung or broke the contract: a failed check, not bad input. Its words
    // (name, exception text) and what it printed reach the terminal without their control characters.
    fmt::print(stderr, "twinray: error: {}\n", twinray::one_line(e.what()));
    if (!e.output.empty())
      fmt::print(stderr, "plugin output (stdout and stderr):\n{}\n", twinray::printable_lines(e.output));
    return kExitCheckFailed;
  } catch (const twinray::PluginBuildError& e) {
    // The plugin declined the scene: the plugin under test failed, the input is fine.
    fmt::print(stderr, "twinray: error: {}\n", twinray::one_line(e.what()));
    return kExitCheckFailed;
  } catch (const std::exception& e) {
    fmt::print(stderr, "twinray: error: {}\n", twinray::one_line(e.what()));
    return kExitBadInput;
  }
}
