// twinray-plugin-worker: runs one plugin for twinray, in a sandbox, and nothing else.
//
//   twinray-plugin-worker /absolute/path/libplugin.so      (started by twinray, never by hand)
//
// Started by twinray's isolated plugin backend (backends/plugin/isolated_plugin_backend.h) with the shared
// memory of worker_protocol.h as fd 3, a lifeline pipe as fd 4 and its output into a pipe on fds 1 and 2.
// The order below matters:
//   1. crash recorder and resource limits, before any plugin code can run;
//   2. Landlock and the first (loading) seccomp filter, on the only thread, so every later thread inherits
//      them (Landlock cannot be applied to threads that already exist);
//   3. the query threads, one per channel;
//   4. dlopen, checks and create() (PluginLibrary, the same code as the in-process backend); the result or
//      the load error goes to the header and twinray is woken;
//   5. build (on a query thread), after which the second (querying) seccomp filter forbids opening files;
//   6. the main thread waits on the lifeline: when twinray is gone, so is the worker.

#include "backends/plugin/futex.h"
#include "backends/plugin/plugin_library.h"
#include "backends/plugin/worker/crash_recorder.h"
#include "backends/plugin/worker/landlock_rules.h"
#include "backends/plugin/worker/query_server.h"
#include "backends/plugin/worker/resource_limits.h"
#include "backends/plugin/worker/sanitizer_hooks.h"
#include "backends/plugin/worker/seccomp_filter.h"
#include "backends/plugin/worker_protocol.h"
#include "core/util/input_error.h"

#include <malloc.h>
#include <poll.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <climits>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <string>

namespace pw = twinray::plugin_worker;

namespace {

// Exit codes for a worker that cannot even reach its header (twinray reports them as a failed start).
constexpr int kExitUsage = 120;
constexpr int kExitNoControlBlock = 121;

void copy_text(char* destination, std::size_t capacity, const std::string& text) {
  const std::size_t n = std::min(capacity - 1, text.size());
  std::memcpy(destination, text.data(), n);
  destination[n] = '\0';
}

void announce(pw::Header& header, pw::Startup state) {
  header.startup.store(static_cast<std::uint32_t>(state), std::memory_order_release);
  pw::futex_wake_all(&header.startup);
}

// Blocks until twinray closes its end of the lifeline (or dies), then ends the worker.
[[noreturn]] void wait_for_twinray() {
  for (;;) {
    pollfd fd{pw::kLifelineFd, POLLIN, 0};
    if (poll(&fd, 1, -1) > 0 && (fd.revents & (POLLIN | POLLHUP | POLLERR | POLLNVAL)) != 0) _exit(0);
  }
}

[[noreturn]] void setup_failed(pw::Header& header, const std::string& why) {
  copy_text(header.message, sizeof header.message, why);
  announce(header, pw::Startup::SetupFailed);
  wait_for_twinray();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return kExitUsage;
  // Nothing but 0-4 should be open (twinray's spawn closes the rest); make sure.
  close_range(pw::kLifelineFd + 1, ~0U, 0);

  struct stat st {};
  if (fstat(pw::kControlFd, &st) != 0 || static_cast<std::size_t>(st.st_size) < sizeof(pw::ControlBlock))
    return kExitNoControlBlock;
  void* mapping = mmap(nullptr, sizeof(pw::ControlBlock), PROT_READ | PROT_WRITE, MAP_SHARED, pw::kControlFd, 0);
  if (mapping == MAP_FAILED) return kExitNoControlBlock;
  auto& block = *static_cast<pw::ControlBlock*>(mapping);
  pw::Header& header = block.header;
  if (header.magic != pw::kMagic || header.version != pw::kProtocolVersion)
    setup_failed(header, "twinray and twinray-plugin-worker come from different builds (protocol mismatch)");

  // glibc's malloc reads /proc/sys/vm/overcommit_memory the first time it shrinks a thread's heap, which would
  // be a forbidden open once the querying filter is in place (a plugin freeing memory in a query would be
  // stopped as a sandbox violation). Heaps of threads never shrink below this trim threshold: 2 GiB, more than
  // one such heap can hold (64 MiB). Memory a plugin frees stays with the worker, which ends with the instance.
  mallopt(M_TRIM_THRESHOLD, INT_MAX);
  // Every malloc arena reserves 64 MiB of address space, which counts against RLIMIT_AS whether used or not;
  // glibc would make up to eight per core as threads first allocate. Four bound the reservation at 256 MiB
  // and still let four threads allocate without contention (queries should not allocate at all).
  mallopt(M_ARENA_MAX, 4);

  // stdout is a pipe, which stdio would buffer in 4 KiB blocks: the last lines a plugin prints before it
  // crashes would be lost with the buffer. Line buffering keeps them (std::cout shares stdio's buffer).
  std::setvbuf(stdout, nullptr, _IOLBF, 0);

  pw::install_crash_recorder(header.crash);
  pw::install_sanitizer_hooks(header.crash);
  pw::set_thread_role(pw::kMainThread);
  pw::install_alternate_signal_stack();

  std::string sandbox;
  try {
    sandbox = pw::apply_resource_limits(header.memory_bytes);
  } catch (const std::exception& e) {
    setup_failed(header, e.what());
  }
  const std::filesystem::path plugin_path = argv[1];
  const pw::LandlockOutcome landlock = pw::restrict_file_system(plugin_path);
  const std::string filter_error = pw::install_seccomp_filter(pw::FilterPhase::Loading);
  const bool seccomp_active = filter_error.empty();
  sandbox = landlock.description + "; " +
            (seccomp_active ? "seccomp allow-list (after build: no opening files; never: processes, sockets, ptrace)"
                            : "seccomp unavailable (" + filter_error + ")") +
            "; " + sandbox;
  copy_text(header.sandbox, sizeof header.sandbox, sandbox);
  header.sandbox_complete = landlock.applied && seccomp_active ? 1 : 0;

  pw::QueryServer server(block, pw::kControlFd, [seccomp_active] {
    return seccomp_active ? pw::install_seccomp_filter(pw::FilterPhase::Querying) : std::string();
  });
  try {
    server.start_threads();
  } catch (const std::exception& e) {  // std::system_error: no memory for 16 stacks under a tiny limit
    setup_failed(header, std::string("cannot start the query threads (is the memory limit too low?): ") + e.what());
  }

  std::unique_ptr<twinray::PluginLibrary> plugin;
  header.loading.store(1);
  try {
    plugin = twinray::PluginLibrary::load(plugin_path);
  } catch (const twinray::InputError& e) {
    header.loading.store(0);
    copy_text(header.message, sizeof header.message, e.message());
    announce(header, pw::Startup::LoadFailed);
    wait_for_twinray();
  }
  header.loading.store(0);
  server.set_plugin(*plugin);
  const twinray_plugin_v1& table = plugin->table();
  copy_text(header.plugin_name, sizeof header.plugin_name, table.name);
  header.plugin_flags = table.flags;
  header.batch_functions = (table.intersect_batch != nullptr ? pw::kHasIntersectBatch : 0u) |
                           (table.occluded_batch != nullptr ? pw::kHasOccludedBatch : 0u);
  announce(header, pw::Startup::Ready);
  wait_for_twinray();
}
