#pragma once
// Runs the real `twinray` binary from tests: exit code and captured output, so the public contract
// (exit codes, messages, JSON keys, no partial output files) is tested end to end.

#include <cstdio>
#include <filesystem>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace twinray::testing {

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr, interleaved
};

// Any shell command line (sh -c), stdout and stderr captured together.
inline CommandResult run_command(const std::string& command_line) {
  const std::string command = command_line + " 2>&1";
  CommandResult result;
  std::FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return result;
  char buffer[4096];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) result.output.append(buffer, n);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}

// `wrapper` runs before the binary, e.g. "setpriv --reuid=65534 " to run it as another user.
inline CommandResult run_twinray(const std::string& args, const std::string& wrapper = "") {
  std::string command = "CI=true ";
  command.append(wrapper).append("'").append(TWINRAY_BINARY).append("' ").append(args);
  return run_command(command);
}

inline std::filesystem::path source_path(const std::string& relative) {
  return std::filesystem::path(TWINRAY_SOURCE_DIR) / relative;
}

// A fresh, empty folder for one test's files.
// Keyed by the process as well as the name: ctest runs every test in its own process, and two checkouts (or two
// ctest runs) on one machine must not remove each other's folders mid-test.
inline std::filesystem::path scratch_dir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("twinray-test-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::string quoted(const std::filesystem::path& p) {
  std::string s = "'";
  s.append(p.string()).append("'");
  return s;
}

}  // namespace twinray::testing
