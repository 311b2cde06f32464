#pragma once
// The worker's system-call sandbox (seccomp, through libseccomp): an allow-list, everything else stopped
// with SIGSYS (SCMP_ACT_TRAP), which the crash recorder reports with the system call's number.
//
// Two phases, each an allow-list; seccomp filters stack, so once both are installed only calls allowed by
// both pass:
//   Loading   installed before dlopen: what a plugin needs to run (memory, threads, time, I/O on descriptors
//             already open) plus what loading a library needs (opening files read-only, stat, access) and
//             seccomp itself, to install the second phase. Landlock decides which files may be read.
//   Querying  installed after build, before the first query: the same minus everything that names a path.
// Never allowed: processes (fork, vfork, clone without CLONE_THREAD, execve), sockets, ptrace and
// process_vm_readv/writev, io_uring, bpf, perf_event_open, mount, namespaces, keyctl, signals to other
// processes, changing resource limits, and any file modification.

#include <string>

namespace twinray::plugin_worker {

enum class FilterPhase { Loading, Querying };

// Installs the phase's filter on every thread of the process (TSYNC). Returns an empty string on success,
// else why it failed.
std::string install_seccomp_filter(FilterPhase phase);

}  // namespace twinray::plugin_worker
