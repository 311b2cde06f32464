#include "backends/plugin/worker/seccomp_filter.h"

#include "backends/plugin/sanitizer_build.h"
#include "backends/plugin/worker_protocol.h"  // kControlFd, kLifelineFd

#include <sys/ioctl.h>  // TCGETS, TIOCGWINSZ
#include <fcntl.h>
#include <linux/sched.h>   // CLONE_THREAD
#include <seccomp.h>
#include <signal.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>

namespace twinray::plugin_worker {

namespace {

struct ContextDeleter {
  void operator()(scmp_filter_ctx ctx) const { seccomp_release(ctx); }
};
using Context = std::unique_ptr<void, ContextDeleter>;

struct Builder {
  scmp_filter_ctx ctx;
  int error = 0;
  const char* failed = nullptr;

  void allow(int syscall, const char* name) { add(SCMP_ACT_ALLOW, syscall, name, 0, nullptr); }
  void allow_if(int syscall, const char* name, scmp_arg_cmp cmp) { add(SCMP_ACT_ALLOW, syscall, name, 1, &cmp); }
  void add(std::uint32_t action, int syscall, const char* name, unsigned count, const scmp_arg_cmp* cmp) {
    const int rc = seccomp_rule_add_array(ctx, action, syscall, count, cmp);
    if (rc != 0 && error == 0) {
      error = rc;
      failed = name;
    }
  }
};

// One argument comparison (libseccomp's SCMP_A0..SCMP_A5 macros are C99 compound literals).
constexpr scmp_arg_cmp arg(unsigned index, scmp_compare op, scmp_datum_t a, scmp_datum_t b = 0) {
  return scmp_arg_cmp{index, op, a, b};
}

#define ALLOW(name) b.allow(SCMP_SYS(name), #name)
#define ALLOW_IF(name, cmp) b.allow_if(SCMP_SYS(name), #name, cmp)

// What any plugin may do at any time. Each line says why it is needed.
void allow_running(Builder& b) {
  // Memory: malloc/new (brk, mmap, munmap, mremap), thread stacks and guard pages (mprotect), allocators
  // returning memory (madvise).
  ALLOW(brk);
  ALLOW(mmap);
  ALLOW(munmap);
  ALLOW(mremap);
  ALLOW(mprotect);
  ALLOW(madvise);
  // Threads: std::thread / pthread_create is clone with CLONE_THREAD (a new process is not), plus what glibc
  // sets up per thread and what mutexes and condition variables wait on.
  ALLOW_IF(clone, arg(0, SCMP_CMP_MASKED_EQ, CLONE_THREAD, CLONE_THREAD));
  // clone3 passes its flags in memory, which a filter cannot read: "not implemented", and glibc falls back to
  // clone, whose flags are checked above.
  b.add(SCMP_ACT_ERRNO(ENOSYS), SCMP_SYS(clone3), "clone3", 0, nullptr);
  ALLOW(futex);
  ALLOW(set_robust_list);
  ALLOW(rseq);
  ALLOW(set_tid_address);
  ALLOW(exit);
  ALLOW(exit_group);
  ALLOW(gettid);
  ALLOW(getpid);
  ALLOW(sched_yield);
  ALLOW(sched_getaffinity);  // std::thread::hardware_concurrency, OpenMP, TBB
  ALLOW(sched_setaffinity);  // thread pinning by a parallel builder; affects only the worker
  ALLOW(sched_getparam);     // pthread attributes
  ALLOW(sched_getscheduler);
  ALLOW(getcpu);
  // Signals: handlers and masks (a plugin may install its own), returning from handlers, alternate stacks.
  // Only SIGSYS is off limits: its handler is how a forbidden call is reported.
  ALLOW_IF(rt_sigaction, arg(0, SCMP_CMP_NE, SIGSYS));
  ALLOW(rt_sigprocmask);
  ALLOW(rt_sigreturn);
  ALLOW(sigaltstack);
  ALLOW(restart_syscall);
  // abort() and raise() signal the calling thread; the crash recorder re-raises a fatal signal the same way.
  // Only threads of this process (tgkill's first argument is the process id).
  ALLOW_IF(tgkill, arg(0, SCMP_CMP_EQ, static_cast<scmp_datum_t>(getpid())));
  // Time: mostly served by the vDSO without a system call; these are the fallbacks and sleeps.
  ALLOW(clock_gettime);
  ALLOW(clock_getres);
  ALLOW(gettimeofday);
  ALLOW(time);
  ALLOW(nanosleep);
  ALLOW(clock_nanosleep);
  ALLOW(getrusage);  // timing code, and AddressSanitizer's resident-memory limit in sanitizer builds
  ALLOW(times);
  // I/O on descriptors that are already open (stdout and stderr into twinray's pipe, the shared memory, the
  // lifeline): printing, and the worker's own waiting. Opening anything is not in this list.
  ALLOW(read);
  ALLOW(write);
  ALLOW(readv);
  ALLOW(writev);
  ALLOW(pread64);
  ALLOW(lseek);
  // Closing or replacing (dup2, dup3) the worker's own descriptors 3 (the shared memory) and 4 (the lifeline)
  // is refused: with 4 gone, the worker would end as if twinray had, at a moment that depends on its threads'
  // timing, and be reported as having called exit(0) somewhere else. Refused, it is one deterministic sandbox
  // failure naming the call. Everything else a plugin may close (its own files, even stdout and stderr).
  b.allow_if(SCMP_SYS(close), "close", arg(0, SCMP_CMP_LT, kControlFd));
  b.allow_if(SCMP_SYS(close), "close", arg(0, SCMP_CMP_GT, kLifelineFd));
  ALLOW(fstat);
  // glibc's fstat is newfstatat(fd, "", AT_EMPTY_PATH); with a path it would tell whether files exist.
  ALLOW_IF(newfstatat, arg(3, SCMP_CMP_MASKED_EQ, AT_EMPTY_PATH, AT_EMPTY_PATH));
  ALLOW(fcntl);
  ALLOW(dup);
  b.allow_if(SCMP_SYS(dup2), "dup2", arg(1, SCMP_CMP_LT, kControlFd));
  b.allow_if(SCMP_SYS(dup2), "dup2", arg(1, SCMP_CMP_GT, kLifelineFd));
  b.allow_if(SCMP_SYS(dup3), "dup3", arg(1, SCMP_CMP_LT, kControlFd));
  b.allow_if(SCMP_SYS(dup3), "dup3", arg(1, SCMP_CMP_GT, kLifelineFd));
  ALLOW(poll);
  ALLOW(ppoll);
  // isatty() (stdio decides on buffering) and the terminal's width: harmless queries, on a pipe they fail.
  ALLOW_IF(ioctl, arg(1, SCMP_CMP_EQ, TCGETS));
  ALLOW_IF(ioctl, arg(1, SCMP_CMP_EQ, TIOCGWINSZ));
  // Reading limits (getrlimit is prlimit64 with no new limit); setting them is not allowed.
  ALLOW_IF(prlimit64, arg(2, SCMP_CMP_EQ, 0));
  ALLOW(getrlimit);
  // Facts about the system: sysconf (memory size, CPU count), uname, ids.
  ALLOW(sysinfo);
  ALLOW(uname);
  ALLOW(getuid);
  ALLOW(geteuid);
  ALLOW(getgid);
  ALLOW(getegid);
  ALLOW(getrandom);  // std::random_device
  // Thread names (pthread_setname_np on the calling thread).
  ALLOW_IF(prctl, arg(0, SCMP_CMP_EQ, PR_SET_NAME));
  ALLOW_IF(prctl, arg(0, SCMP_CMP_EQ, PR_GET_NAME));
}

// What loading a library (dlopen, its dependencies, static constructors, create and build) adds.
void allow_loading(Builder& b) {
  // Opening files read-only; which files is Landlock's decision (landlock_rules.h). Creating, truncating,
  // writing and appending are refused here whatever Landlock says.
  ALLOW_IF(openat, arg(2, SCMP_CMP_MASKED_EQ, O_ACCMODE | O_CREAT | O_TRUNC | O_APPEND, O_RDONLY));
  ALLOW(newfstatat);  // any path: the loader stats candidates
  ALLOW(statx);
  ALLOW(access);      // /etc/ld.so.preload
  ALLOW(faccessat);
  ALLOW(faccessat2);
  ALLOW(readlink);
  ALLOW(readlinkat);
  ALLOW(getdents64);  // a builder's thread pool may list /sys/devices/system/cpu
  ALLOW(fstatfs);
  // Installing the querying phase's filter after build (it only ever narrows what is allowed).
  ALLOW(seccomp);
}

// What AddressSanitizer's runtime does in the worker of a sanitizer build (scripts/sanitize.sh), besides what
// is allowed above: it checks whether memory is readable by writing it into a pipe (IsAccessibleMemoryRange,
// used while loading libraries and unwinding).
void allow_sanitizer_runtime(Builder& b) {
  ALLOW(pipe2);
}

#undef ALLOW
#undef ALLOW_IF

}  // namespace

std::string install_seccomp_filter(FilterPhase phase) {
  const Context ctx(seccomp_init(SCMP_ACT_TRAP));
  if (!ctx) return "seccomp_init failed";
  Builder b{ctx.get()};
  allow_running(b);
  if (phase == FilterPhase::Loading) allow_loading(b);
  if constexpr (kAddressSanitizer) allow_sanitizer_runtime(b);
  if (b.error != 0) return std::string("seccomp rule for ") + b.failed + ": " + std::strerror(-b.error);
  // TSYNC: the filter reaches every thread, including the query threads and the plugin's own.
  seccomp_attr_set(ctx.get(), SCMP_FLTATR_CTL_TSYNC, 1);
  // no_new_privs is set once, before the first filter (landlock_rules.cpp); the second phase must not ask
  // again, since prctl(PR_SET_NO_NEW_PRIVS) is not on the list by then.
  if (phase == FilterPhase::Querying) seccomp_attr_set(ctx.get(), SCMP_FLTATR_CTL_NNP, 0);
  else prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0);
  const int rc = seccomp_load(ctx.get());
  if (rc != 0) return std::string("seccomp_load failed: ") + std::strerror(-rc);
  return {};
}

}  // namespace twinray::plugin_worker
