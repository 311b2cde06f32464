#include "backends/plugin/worker/crash_recorder.h"

#include "backends/plugin/futex.h"

#include <signal.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>

namespace twinray::plugin_worker {

namespace {

CrashRecord* g_record = nullptr;
std::atomic<bool> g_clean_exit{false};
// Constant-initialised, so reading it in a signal handler touches no lazily created state.
thread_local std::int32_t t_role = kPluginThread;

constexpr int kFatalSignals[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS};
constexpr std::size_t kAlternateStackBytes = 64 * 1024;

// The first fatal event wins; a second thread crashing at the same moment does not overwrite it.
bool claim(std::uint32_t what) {
  std::uint32_t none = kCrashNone;
  return g_record != nullptr && g_record->what.compare_exchange_strong(none, what);
}

void on_fatal_signal(int sig, siginfo_t* info, void*) {
  const int saved_errno = errno;  // first: anything below could change it
  if (claim(kCrashSignal)) {
    g_record->signal.store(sig);
    g_record->thread.store(t_role);
    // The worker sets errno to 0 before every plugin call, so ENOMEM here means an allocation failed during
    // this call (malloc returns NULL with errno ENOMEM at the RLIMIT_AS limit); the crash is its consequence.
    // Only ever set, never cleared: a sanitizer's out-of-memory report may have set it already.
    if (saved_errno == ENOMEM) g_record->allocation_failed.store(1);
    if (sig == SIGSYS) g_record->syscall.store(info->si_syscall);
  }
  // SA_RESETHAND has already restored the default action. Re-raise for this thread: the signal is blocked
  // while the handler runs and is delivered, fatally, as it returns. (For a fault, returning would re-execute
  // the faulting instruction anyway; for SIGSYS and raised signals it would not.)
  syscall(SYS_tgkill, getpid(), gettid(), sig);
}

void on_exit_called() {
  const int saved_errno = errno;
  if (g_clean_exit.load()) {  // the worker's own exit after destroy (expect_clean_exit)
    if (g_record != nullptr) {
      g_record->exit_handlers_done.store(1);
      futex_wake_all(&g_record->exit_handlers_done);
    }
    return;
  }
  if (claim(kCrashExit)) {
    g_record->thread.store(t_role);
    if (saved_errno == ENOMEM) g_record->allocation_failed.store(1);
  }
}

}  // namespace

void install_crash_recorder(CrashRecord& record) {
  g_record = &record;
  struct sigaction action {};
  action.sa_sigaction = on_fatal_signal;
  action.sa_flags = SA_SIGINFO | SA_ONSTACK | SA_RESETHAND;
  sigfillset(&action.sa_mask);  // nothing interrupts the recording
  for (const int sig : kFatalSignals) sigaction(sig, &action, nullptr);
  // The worker itself calls exit() only after destroy (expect_clean_exit), so an atexit handler running before
  // that means plugin code called exit(). Registered before the plugin is loaded, it runs after the plugin's
  // own handlers. _exit() from plugin code runs no handler; twinray then attributes it by the channel that was
  // running plugin code.
  std::atexit(on_exit_called);
}

void set_thread_role(std::int32_t role) { t_role = role; }

void expect_clean_exit() { g_clean_exit.store(true); }

void install_alternate_signal_stack() {
  void* memory = mmap(nullptr, kAlternateStackBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (memory == MAP_FAILED) return;  // without it, an overflow still kills the worker; only attribution suffers
  stack_t stack{};
  stack.ss_sp = memory;
  stack.ss_size = kAlternateStackBytes;
  sigaltstack(&stack, nullptr);
}

}  // namespace twinray::plugin_worker
