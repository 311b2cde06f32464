#pragma once
// Which thread of the worker was doing what when it died, written to shared memory for twinray to read after
// the worker is gone (worker_protocol.h, CrashRecord).
//
// Every fatal signal (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP and the seccomp filter's SIGSYS) gets a
// handler that records the signal, the role of the thread it hit (its channel, the main thread, or a thread
// the plugin made), the system call for SIGSYS, and whether an allocation had just failed (errno ENOMEM); it
// then ends the worker with that same signal, so twinray sees the true cause in the exit status. An atexit
// handler records exit() called from plugin code the same way. The handlers use async-signal-safe stores only.

#include "backends/plugin/worker_protocol.h"

#include <cstdint>

namespace twinray::plugin_worker {

// Installs the handlers and the atexit hook; `record` must stay mapped for the life of the process.
void install_crash_recorder(CrashRecord& record);

// The calling thread's role for the record: a channel index, or kMainThread. Threads that never call this
// (the plugin's own) are recorded as kPluginThread.
void set_thread_role(std::int32_t role);

// The worker itself is about to call exit() (after destroy, so that the plugin's atexit handlers and static
// destructors run as they would at the end of a program): from now on the atexit hook records nothing.
void expect_clean_exit();

// Gives the calling thread its own signal stack, so that the handler still runs (and the crash is attributed
// to the thread's channel) when plugin code overflows the thread's stack.
void install_alternate_signal_stack();

}  // namespace twinray::plugin_worker
