#pragma once
// Subcommands of the `twinray` program. Each add_*_command registers its options on a CLI11 subcommand
// and sets `run`, which main() calls after parsing. The return value is the process exit code:
//   0 success, 1 the check or comparison failed, 2 bad input (message on stderr, no output left behind).

#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <functional>
#include <string_view>

namespace twinray::cli {

inline constexpr int kExitOk = 0;
inline constexpr int kExitCheckFailed = 1;
inline constexpr int kExitBadInput = 2;

using CommandRunner = std::function<int()>;

// Prints "twinray COMMAND: error: MESSAGE" on stderr and returns kExitBadInput: the one shape of every
// bad-input message, which scripts and the CLI contract tests match.
inline int report_bad_input(std::string_view command, std::string_view message) {
  fmt::print(stderr, "twinray {}: error: {}\n", command, message);
  return kExitBadInput;
}

void add_info_command(CLI::App& app, CommandRunner& run);
void add_crosscheck_command(CLI::App& app, CommandRunner& run);
void add_render_command(CLI::App& app, CommandRunner& run);
void add_stress_command(CLI::App& app, CommandRunner& run);
void add_converge_command(CLI::App& app, CommandRunner& run);
void add_report_command(CLI::App& app, CommandRunner& run);
void add_export_command(CLI::App& app, CommandRunner& run);
void add_compare_command(CLI::App& app, CommandRunner& run);
void add_trace_command(CLI::App& app, CommandRunner& run);
void add_grade_command(CLI::App& app, CommandRunner& run);

}  // namespace twinray::cli
