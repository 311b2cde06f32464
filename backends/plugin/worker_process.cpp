#include "backends/plugin/worker_process.h"

#include "backends/plugin/output_capture.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/core.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <system_error>

namespace twinray {

namespace {

constexpr const char* kWorkerName = "twinray-plugin-worker";

bool is_executable_file(const std::filesystem::path& p) {
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec) && access(p.c_str(), X_OK) == 0;
}

std::runtime_error system_failure(const std::string& what, int error) {
  return std::runtime_error(fmt::format("cannot start the plugin worker: {}: {}", what, std::strerror(error)));
}

// Closes a file descriptor on every exit path of the constructor.
struct Fd {
  int fd = -1;
  Fd() = default;
  explicit Fd(int f) : fd(f) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() {
    if (fd >= 0) close(fd);
  }
  int release() {
    const int f = fd;
    fd = -1;
    return f;
  }
};

// The raw system calls: glibc 2.36's <sys/pidfd.h> lacks the C++ linkage guards.
int open_pidfd(pid_t pid) { return static_cast<int>(syscall(SYS_pidfd_open, pid, 0)); }
void send_kill(int pidfd) { syscall(SYS_pidfd_send_signal, pidfd, SIGKILL, nullptr, 0); }

// A close-on-exec duplicate numbered 10 or above, so that the dup2 calls of the spawn (onto 0 to 4) never
// overwrite a source that happens to have a low number (a parent whose stdin or stdout is closed).
Fd high_duplicate(int fd) {
  const int h = fcntl(fd, F_DUPFD_CLOEXEC, 10);
  if (h < 0) throw system_failure("fcntl(F_DUPFD_CLOEXEC)", errno);
  return Fd(h);
}

// posix_spawn's attributes and file actions, destroyed on every exit path.
struct SpawnSetup {
  posix_spawn_file_actions_t actions;
  posix_spawnattr_t attributes;
  SpawnSetup() {
    posix_spawn_file_actions_init(&actions);
    posix_spawnattr_init(&attributes);
  }
  ~SpawnSetup() {
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attributes);
  }
  SpawnSetup(const SpawnSetup&) = delete;
  SpawnSetup& operator=(const SpawnSetup&) = delete;
};

}  // namespace

std::filesystem::path find_plugin_worker() {
  if (const char* env = std::getenv("TWINRAY_PLUGIN_WORKER"); env != nullptr && env[0] != '\0') {
    // An explicit choice is never silently replaced by another worker.
    if (!is_executable_file(env))
      throw std::runtime_error(
          fmt::format("TWINRAY_PLUGIN_WORKER is set to '{}', which is not an executable file", env));
    return env;
  }
  std::vector<std::string> looked;
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const std::filesystem::path beside = self.parent_path() / kWorkerName;
    if (is_executable_file(beside)) return beside;
    looked.push_back(beside.string());
  }
#ifdef TWINRAY_PLUGIN_WORKER_BUILD_PATH
  const std::filesystem::path built = TWINRAY_PLUGIN_WORKER_BUILD_PATH;
  if (is_executable_file(built)) return built;
  looked.push_back(built.string());
#endif
  std::string places;
  for (const std::string& p : looked) places += (places.empty() ? "" : ", ") + p;
  throw std::runtime_error(fmt::format(
      "cannot find the plugin worker '{}' (looked at {}): build the target {} or set TWINRAY_PLUGIN_WORKER to its "
      "path (plugin-inprocess:PATH runs a trusted plugin without it)",
      kWorkerName, places.empty() ? "nothing" : places, kWorkerName));
}

WorkerProcess::WorkerProcess(const std::filesystem::path& executable, const std::vector<std::string>& args,
                             const std::vector<std::string>& environment, int control_fd, std::size_t output_limit,
                             std::function<void(const WorkerTermination&)> on_exit)
    : on_exit_(std::move(on_exit)), output_(std::make_unique<OutputCapture>(output_limit)) {
  int output_pipe[2];
  int lifeline_pipe[2];
  if (pipe2(output_pipe, O_CLOEXEC) != 0) throw system_failure("pipe2", errno);
  Fd output_read(output_pipe[0]), output_write(output_pipe[1]);
  if (pipe2(lifeline_pipe, O_CLOEXEC) != 0) throw system_failure("pipe2", errno);
  Fd lifeline_read(lifeline_pipe[0]), lifeline_write(lifeline_pipe[1]);

  const Fd output_high = high_duplicate(output_write.fd);
  const Fd control_high = high_duplicate(control_fd);
  const Fd lifeline_high = high_duplicate(lifeline_read.fd);

  SpawnSetup setup;
  posix_spawn_file_actions_addopen(&setup.actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&setup.actions, output_high.fd, 1);
  posix_spawn_file_actions_adddup2(&setup.actions, output_high.fd, 2);
  posix_spawn_file_actions_adddup2(&setup.actions, control_high.fd, 3);
  posix_spawn_file_actions_adddup2(&setup.actions, lifeline_high.fd, 4);
  // Everything else is closed, whether or not it was opened close-on-exec (a library's stray descriptor
  // would otherwise give plugin code a file twinray has open).
  posix_spawn_file_actions_addclosefrom_np(&setup.actions, 5);
  // Default actions and an empty mask for every signal: twinray (or its caller) may ignore SIGPIPE or block
  // signals, and the worker's crash reporting must see them as the kernel delivers them.
  sigset_t none, all;
  sigemptyset(&none);
  sigfillset(&all);
  sigdelset(&all, SIGKILL);
  sigdelset(&all, SIGSTOP);
  posix_spawnattr_setsigmask(&setup.attributes, &none);
  posix_spawnattr_setsigdefault(&setup.attributes, &all);
  posix_spawnattr_setflags(&setup.attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);

  std::vector<std::string> argv_strings;
  argv_strings.push_back(executable.string());
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& s : argv_strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_strings = environment;
  std::vector<char*> envp;
  for (std::string& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);

  // posix_spawn, not fork: the child is a fresh program image from the start, so no page of twinray's
  // memory (the scene's expected answers, a grading suite) is ever mapped in it.
  const int error = posix_spawn(&pid_, executable.c_str(), &setup.actions, &setup.attributes, argv.data(), envp.data());
  if (error != 0) throw system_failure(executable.string(), error);

  pidfd_ = open_pidfd(pid_);
  if (pidfd_ < 0) {
    const int e = errno;
    ::kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    throw system_failure("pidfd_open (Linux 5.3 or later is needed)", e);
  }
  // Non-blocking: output() reads what is there without waiting for more.
  fcntl(output_read.fd, F_SETFL, fcntl(output_read.fd, F_GETFL) | O_NONBLOCK);
  output_fd_ = output_read.release();
  lifeline_fd_ = lifeline_write.release();
  monitor_ = std::thread([this] { monitor(); });
}

WorkerProcess::~WorkerProcess() {
  kill();
  if (monitor_.joinable()) monitor_.join();
  if (pidfd_ >= 0) close(pidfd_);
  if (output_fd_ >= 0) close(output_fd_);
  close_lifeline();
}

void WorkerProcess::kill() {
  std::lock_guard lock(mutex_);
  if (termination_) return;
  kill_sent_ = true;
  send_kill(pidfd_);
}

void WorkerProcess::close_lifeline() {
  std::lock_guard lock(mutex_);
  if (lifeline_fd_ >= 0) close(lifeline_fd_);
  lifeline_fd_ = -1;
}

bool WorkerProcess::running() const {
  std::lock_guard lock(mutex_);
  return !termination_;
}

bool WorkerProcess::wait_for_exit(std::chrono::steady_clock::duration timeout) {
  std::unique_lock lock(mutex_);
  return ended_.wait_for(lock, timeout, [this] { return termination_.has_value(); });
}

std::optional<WorkerTermination> WorkerProcess::termination() const {
  std::lock_guard lock(mutex_);
  return termination_;
}

std::string WorkerProcess::output() const {
  drain_available();
  std::lock_guard lock(mutex_);
  return output_->text();
}

bool WorkerProcess::drain_available() const {
  std::lock_guard read_lock(read_mutex_);
  char buffer[64 * 1024];
  while (output_open_) {
    const ssize_t n = read(output_fd_, buffer, sizeof buffer);
    if (n > 0) {
      std::lock_guard lock(mutex_);
      output_->append(std::string_view(buffer, static_cast<std::size_t>(n)));
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else if (n < 0 && errno == EAGAIN) {
      break;
    } else {
      output_open_ = false;  // end of file (or an error, which means the same here)
    }
  }
  return output_open_;
}

void WorkerProcess::monitor() {
  bool output_open = true;
  for (;;) {
    pollfd fds[2] = {{pidfd_, POLLIN, 0}, {output_fd_, POLLIN, 0}};
    if (poll(fds, output_open ? 2 : 1, -1) < 0) {
      if (errno == EINTR) continue;
      break;  // cannot happen with valid descriptors; reap below rather than spin
    }
    if (output_open && (fds[1].revents & (POLLIN | POLLHUP | POLLERR)) != 0) output_open = drain_available();
    if ((fds[0].revents & (POLLIN | POLLHUP | POLLERR)) != 0) break;
  }

  siginfo_t info{};
  while (waitid(P_PIDFD, static_cast<id_t>(pidfd_), &info, WEXITED) != 0 && errno == EINTR) {
  }
  WorkerTermination t;
  t.exited = info.si_code == CLD_EXITED;
  if (t.exited) t.exit_code = info.si_status;
  else t.signal = info.si_status;

  // The rest of the output: the worker held the only write ends of the pipe, so EOF follows at once. A bound
  // all the same, in case something the worker started still holds one.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
  while (output_open) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(give_up - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    pollfd fd{output_fd_, POLLIN, 0};
    const int ready = poll(&fd, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) break;
    output_open = drain_available();
  }

  {
    std::lock_guard lock(mutex_);
    t.killed_by_twinray = kill_sent_;
  }
  // Wake every waiting caller before anyone can see the worker as ended (and, say, unmap the memory the
  // callback touches).
  if (on_exit_) on_exit_(t);
  {
    std::lock_guard lock(mutex_);
    termination_ = t;
  }
  ended_.notify_all();
}

}  // namespace twinray
