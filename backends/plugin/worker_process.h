#pragma once
// The plugin worker as a process, seen from twinray: starting it (posix_spawn, never a bare fork, so none of
// twinray's memory is in the worker), capturing what it prints, noticing at once when it dies, and killing it.
//
// A monitor thread per worker waits on the worker's pidfd and its output pipe. It drains the output (so a
// plugin that prints a lot never blocks on a full pipe), reaps the worker when it exits, and then calls
// `on_exit`, which wakes every parent thread still waiting for an answer.

#include <sys/types.h>

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace twinray {

class OutputCapture;

// How the worker ended.
struct WorkerTermination {
  bool exited = false;        // exit() / _exit() / return from main: exit_code is valid
  int exit_code = 0;
  int signal = 0;             // killed by this signal (exited == false)
  bool killed_by_twinray = false;  // WorkerProcess::kill() was called before it ended
};

// Where the worker executable is: $TWINRAY_PLUGIN_WORKER when set (it must exist), else
// twinray-plugin-worker next to the running program (/proc/self/exe), else the path of the build tree
// (baked in by CMake). Throws std::runtime_error listing the places it looked.
std::filesystem::path find_plugin_worker();

class WorkerProcess {
 public:
  // Starts `executable` with `args` (argv[1...]) and exactly this environment. In the worker: fd 0 is
  // /dev/null, fds 1 and 2 one pipe into the capture, fd 3 `control_fd`, fd 4 the read end of the lifeline
  // pipe; nothing else is open and every signal has its default action and is unblocked.
  // Throws std::runtime_error when the worker cannot be started.
  WorkerProcess(const std::filesystem::path& executable, const std::vector<std::string>& args,
                const std::vector<std::string>& environment, int control_fd, std::size_t output_limit,
                std::function<void(const WorkerTermination&)> on_exit);
  ~WorkerProcess();  // kills the worker if it still runs, waits for the monitor
  WorkerProcess(const WorkerProcess&) = delete;
  WorkerProcess& operator=(const WorkerProcess&) = delete;

  pid_t pid() const { return pid_; }
  // SIGKILL (idempotent; nothing happens when it has already ended).
  void kill();
  // Closes the lifeline: the worker's main thread sees EOF and exits on its own.
  void close_lifeline();
  bool running() const;
  // Waits until the worker has ended and the monitor has reaped it and drained its output.
  bool wait_for_exit(std::chrono::steady_clock::duration timeout);
  std::optional<WorkerTermination> termination() const;
  // Everything the worker has printed so far: what is waiting in the pipe is read first, so output printed
  // before the worker answered a call is always included.
  std::string output() const;

 private:
  void monitor();
  // Reads what the pipe holds now, without blocking; false at end of file. Both the monitor and output() call
  // it; read_mutex_ keeps their reads in order.
  bool drain_available() const;

  pid_t pid_ = -1;
  int pidfd_ = -1;
  int output_fd_ = -1;    // read end of the output pipe (the monitor's)
  int lifeline_fd_ = -1;  // write end of the lifeline pipe
  std::function<void(const WorkerTermination&)> on_exit_;

  mutable std::mutex read_mutex_;
  mutable bool output_open_ = true;
  mutable std::mutex mutex_;
  std::condition_variable ended_;
  std::unique_ptr<OutputCapture> output_;
  std::optional<WorkerTermination> termination_;
  bool kill_sent_ = false;
  std::thread monitor_;
};

}  // namespace twinray
