#include "backends/plugin/isolated_plugin_backend.h"

#include "backends/plugin/futex.h"
#include "backends/plugin/geometry_blob.h"
#include "backends/plugin/plugin_hit.h"
#include "backends/plugin/sanitizer_build.h"
#include "backends/plugin/shared_memory.h"
#include "backends/plugin/worker_process.h"
#include "backends/plugin/worker_protocol.h"
#include "core/util/input_error.h"

#include <seccomp.h>
#include <signal.h>

#include <fmt/core.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <mutex>
#include <new>
#include <stdexcept>

namespace twinray {

namespace pw = plugin_worker;

namespace {

using Clock = std::chrono::steady_clock;

// How long a caller waits for the answer (yielding, futex.h) before it sleeps in the kernel. A single ray
// through a simple plugin comes back in one to a few microseconds while the worker thread is awake; a futex
// sleep and wake-up costs ten or more. Longer calls are not worth the system calls of yielding.
constexpr auto kCallerSpin = std::chrono::microseconds(50);
// How long twinray waits for a worker it has killed to be reaped (its output drained) before reporting.
constexpr auto kReapWait = std::chrono::seconds(5);
// How long a worker may take to end after the plugin's exit handlers have run (the C library's teardown, the
// kernel unmapping a large address space on a busy machine), beyond one call's limit.
constexpr auto kTeardownWait = std::chrono::seconds(10);
// Added to every handshake word when the worker dies, so a caller about to sleep on it does not (see
// on_worker_exit).
constexpr std::uint32_t kDeathBump = 1u << 31;

enum class Stage { Load, Build, Intersect, Occluded, Destroy, IntersectBatch, OccludedBatch };

bool is_query(Stage s) {
  return s == Stage::Intersect || s == Stage::Occluded || s == Stage::IntersectBatch || s == Stage::OccludedBatch;
}

const char* stage_name(Stage s) {
  switch (s) {
    case Stage::Load: return "load";
    case Stage::Build: return "build";
    case Stage::Intersect: return "intersect";
    case Stage::Occluded: return "occluded";
    case Stage::Destroy: return "destroy";
    case Stage::IntersectBatch: return "intersect_batch";
    case Stage::OccludedBatch: return "occluded_batch";
  }
  return "?";
}

// A NUL-terminated string written by the worker, which may not have terminated it.
std::string bounded_string(const char* chars, std::size_t capacity) {
  return std::string(chars, strnlen(chars, capacity));
}

std::string signal_name(int sig) {
  const char* abbreviation = sigabbrev_np(sig);
  return abbreviation != nullptr ? std::string("SIG") + abbreviation : fmt::format("signal {}", sig);
}

std::string syscall_name(int number) {
  char* name = seccomp_syscall_resolve_num_arch(SCMP_ARCH_NATIVE, number);
  if (name == nullptr) return fmt::format("syscall {}", number);
  std::string s(name);
  std::free(name);
  return s;
}

// The worker's whole environment: nothing of twinray's but what loading a library may need, and, in a
// sanitizer build, options that keep ASan's own signal handling out of the worker's crash reporting.
std::vector<std::string> worker_environment(const PluginLimits& limits) {
  std::vector<std::string> env;
  // The dynamic loader finds a plugin's dependencies there (the sandbox allows reading those directories).
  if (const char* path = std::getenv("LD_LIBRARY_PATH")) env.push_back(std::string("LD_LIBRARY_PATH=") + path);
  if constexpr (kAddressSanitizer) {
    const auto inherited = [](const char* name) {
      const char* v = std::getenv(name);
      return v != nullptr && v[0] != '\0' ? std::string(v) + ":" : std::string();
    };
    // handle_*=0: a plugin's SIGSEGV, SIGABRT... reach the worker's handler and end the worker with that
    //   signal, instead of ASan printing a report and exiting with its own code.
    // detect_leaks=0: LeakSanitizer stops the world with ptrace and a clone() without CLONE_THREAD at exit,
    //   which the sandbox forbids (the worker ends with exit() after destroy), and leaks of a plugin are not ours.
    // allocator_may_return_null=1: an allocation over the memory limit returns NULL (errno ENOMEM) as glibc's
    //   malloc does, so it is reported as out-of-memory rather than as an ASan report.
    // soft_rss_limit_mb + can_use_proc_maps_statm=0: ASan's primary allocator serves small blocks from address
    //   space reserved at start, which RLIMIT_AS cannot limit; this limit on resident memory can (checked by
    //   ASan's background thread with getrusage, not by opening /proc, which the sandbox forbids).
    // abort_on_error=1, symbolize=0, print_summary=0: an ASan report in the worker (a bug of ours, or `new`
    //   beyond the memory limit, which ASan reports instead of throwing std::bad_alloc) must not need to open
    //   files (the symbolizer would, and the sandbox would stop it half-way); it then ends the worker with
    //   SIGABRT. Unsymbolized reports still name module and offset.
    // detect_stack_use_after_return=0: its fake stacks are mapped lazily, and a mapping that fails at the
    //   memory limit makes ASan read /proc/self/maps on its way out (forbidden); plugins are not instrumented
    //   anyway, so it would only check the worker's own few frames.
    const std::size_t mb = std::max<std::size_t>(1, limits.memory_bytes >> 20);
    env.push_back("ASAN_OPTIONS=" + inherited("ASAN_OPTIONS") +
                  "detect_leaks=0:handle_segv=0:handle_sigbus=0:handle_sigfpe=0:handle_sigill=0:handle_abort=0:"
                  "handle_sigtrap=0:allow_user_segv_handler=1:allocator_may_return_null=1:can_use_proc_maps_statm=0:"
                  "abort_on_error=1:symbolize=0:print_summary=0:detect_stack_use_after_return=0:soft_rss_limit_mb=" + std::to_string(mb));
    const std::string ubsan = inherited("UBSAN_OPTIONS");
    if (!ubsan.empty()) env.push_back("UBSAN_OPTIONS=" + ubsan.substr(0, ubsan.size() - 1));
  }
  return env;
}

// Printed once per process when the worker could not install every layer of the sandbox.
void warn_once_about_sandbox(const std::string& description) {
  static std::atomic<bool> warned{false};
  if (warned.exchange(true)) return;
  std::fprintf(stderr, "twinray: warning: plugin sandbox incomplete on this system: %s\n", description.c_str());
}

// What one channel is doing, for attributing a failure to the exact ray. Parent-private.
struct RequestContext {
  bool active = false;
  Stage stage = Stage::Intersect;
  std::span<const Ray> rays;              // the caller's rays
  const std::size_t* source = nullptr;    // request index -> index into rays (nullptr: the same index)
  std::uint32_t count = 0;
};

struct ChannelSlot {
  std::atomic<bool> busy{false};
  std::uint32_t sequence = 0;  // the last request number posted; only the holder touches it
  mutable std::mutex mutex;    // guards context: the monitor thread reads it when the worker dies
  RequestContext context;
  std::array<std::size_t, pw::kChunkRays> source{};  // a batch chunk's request index -> caller's index
};

}  // namespace

class IsolatedPluginBackend::Impl {
 public:
  Impl(const std::filesystem::path& so, const PluginLimits& limits);
  ~Impl();
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  const std::string& name() const { return name_; }
  BackendTraits traits() const;
  void build(const SceneGeometry& geometry);
  BuildStats build_stats() const { return stats_[instance_]; }
  bool intersect(const Ray& ray, Hit& hit, QueryStats* stats);
  bool occluded(const Ray& ray, QueryStats* stats);
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, QueryStats* stats);
  void occluded(std::span<const Ray> rays, std::span<std::uint8_t> occluded, QueryStats* stats);

  void set_deadline(std::optional<Clock::time_point> deadline) { limits_.deadline = deadline; }
  void use_instance(std::size_t index) {
    if (index >= pw::kInstances) throw std::logic_error(name_ + ": the worker holds only two plugin instances");
    instance_ = static_cast<std::uint32_t>(index);
  }
  const PluginLimits& limits() const { return limits_; }
  void set_batch_path(BatchPath path) { batch_path_ = path; }
  BatchPath batch_path() const { return batch_path_; }
  bool has_intersect_batch() const { return (batch_functions_ & pw::kHasIntersectBatch) != 0; }
  bool has_occluded_batch() const { return (batch_functions_ & pw::kHasOccludedBatch) != 0; }
  std::string captured_output() const { return worker_ ? worker_->output() : std::string(); }
  std::optional<double> worker_cpu_seconds() const;
  std::optional<PluginFailure> failure() const;
  const std::string& sandbox_description() const { return sandbox_; }
  void shutdown();

 private:
  // A channel held for one call: acquired on construction, released (context cleared) on destruction.
  class Lease {
   public:
    explicit Lease(Impl& impl) : impl_(impl), index_(impl.acquire_channel()) {}
    ~Lease() { impl_.release_channel(index_); }
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    std::size_t index() const { return index_; }
    pw::Channel& channel() const { return impl_.block_->channels[index_]; }
    ChannelSlot& slot() const { return impl_.slots_[index_]; }

   private:
    Impl& impl_;
    std::size_t index_;
  };

  std::size_t acquire_channel();
  void release_channel(std::size_t index);
  void set_context(const Lease& lease, const RequestContext& context);

  // Posts the channel's request (`op` on `count` rays, already in the channel) and waits for the answer.
  // Throws PluginFailure when the worker dies, when one plugin call takes longer than `per_call` or the
  // deadline passes (then the worker is killed), or when the answer is one the worker cannot give.
  void round_trip(const Lease& lease, pw::Op op, std::uint32_t count, std::chrono::duration<double> per_call);
  void post(const Lease& lease);
  void wait_for_answer(const Lease& lease, std::uint32_t sequence, std::chrono::duration<double> per_call);
  // An answer the protocol allows: the request as posted, a status its op can have, the ray index where the
  // worker stops (worker_protocol.h). The plugin runs in the worker's process and can write to the shared
  // memory; what it wrote there must end the call at once, not be waited for until a time limit.
  void check_answer(const Lease& lease, pw::Op op, std::uint32_t count, Stage stage);
  void wait_for_startup();

  // The first failure is the one reported; later ones (the worker dying after twinray killed it) are not.
  void record_failure(PluginFailureDetails details, int channel);
  // Kills the worker and waits until it is reaped and its output drained, so the failure carries all of it.
  void end_worker();
  [[noreturn]] void fail(PluginFailureDetails details, int channel);
  [[noreturn]] void fail_timeout(const Lease& lease, Stage stage, bool deadline_passed, double call_seconds,
                                 std::chrono::duration<double> per_call);
  [[noreturn]] void fail_from_status(const Lease& lease, Stage stage);
  [[noreturn]] void fail_corrupted(const Lease& lease, Stage stage, const std::string& what);
  // A result's `found`, which the worker writes as 0 or 1 only.
  bool found_of(const Lease& lease, Stage stage, std::uint32_t found);
  [[noreturn]] void fail_bad_hit(const Lease& lease, Stage stage, std::size_t request_index, const twinray_hit& h);
  // The batch loop shared by intersect and occluded: `miss(i)` resets the answer of ray i, `take(lease, k, i,
  // result)` stores the answer of request slot k (a copy) for ray i.
  template <typename Miss, typename Take>
  void query_in_chunks(std::span<const Ray> rays, pw::Op op, Stage stage, QueryStats* stats, Miss miss, Take take);
  PluginFailure failure_for(int channel) const;
  // Throws failure_for(channel), and remembers that a caller has been told (see shutdown).
  [[noreturn]] void throw_failure(int channel) const;
  void throw_if_failed() const;
  // The ray at `request_index` of the channel's current request: its index in the caller's span and its value.
  // `whole_call`: the failure is the batch call's in flight (a crash, a timeout), not one ray's own answer.
  void attribute_ray(const RequestContext& context, std::uint32_t request_index, PluginFailureDetails& d,
                     bool whole_call = true) const;

  void on_worker_exit(const WorkerTermination& t);
  PluginFailureDetails classify_death(const WorkerTermination& t, int& channel) const;
  PluginFailureDetails base_details() const;

  std::filesystem::path path_;
  PluginLimits limits_;
  std::string name_;
  std::uint32_t flags_ = 0;
  std::uint32_t batch_functions_ = 0;  // pw::kHasIntersectBatch | pw::kHasOccludedBatch
  BatchPath batch_path_ = BatchPath::PluginBatch;
  std::string sandbox_;

  SharedMemoryFile control_file_;
  SharedMapping control_map_;
  pw::ControlBlock* block_;
  std::array<ChannelSlot, pw::kChannels> slots_;
  std::atomic<std::uint32_t> releases_{0};  // bumped on every channel release, for callers waiting for one

  mutable std::mutex failure_mutex_;
  std::optional<PluginFailureDetails> failure_;
  int failure_channel_ = -1;
  std::atomic<bool> ended_{false};          // the worker is gone or being killed: every call throws
  std::atomic<bool> clean_exit_expected_{false};
  // A call has thrown the recorded failure: shutdown() need not report it again. A failure no call has seen
  // (the worker died between calls: a thread of the plugin crashed after the last answer) is shutdown()'s.
  mutable std::atomic<bool> failure_reported_{false};
  bool shut_down_ = false;
  // Per plugin instance in the worker (use_instance): which the calls go to, and each one's build.
  std::uint32_t instance_ = 0;
  std::array<bool, pw::kInstances> built_{};
  std::array<PrimitiveIndex, pw::kInstances> primitives_;
  std::array<BuildStats, pw::kInstances> stats_;

  // Last: destroyed first, so the monitor thread (which calls on_worker_exit) has stopped before any member
  // it touches goes away.
  std::unique_ptr<WorkerProcess> worker_;
};

IsolatedPluginBackend::Impl::Impl(const std::filesystem::path& so, const PluginLimits& limits)
    : path_(so),
      limits_(limits),
      control_file_(round_up(sizeof(pw::ControlBlock), page_size())),
      control_map_(control_file_, 0, control_file_.size()),
      block_(new (control_map_.data()) pw::ControlBlock()) {
  block_->header.control_bytes = control_file_.size();
  block_->header.memory_bytes = limits_.memory_bytes;
  // The worker resolves the path against the same working directory; absolute, so its sandbox can name the
  // plugin's folder.
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(so, ec);
  worker_ = std::make_unique<WorkerProcess>(find_plugin_worker(), std::vector<std::string>{ec ? so.string() : absolute.string()},
                                            worker_environment(limits_), control_file_.fd(), limits_.output_bytes,
                                            [this](const WorkerTermination& t) { on_worker_exit(t); });
  wait_for_startup();
}

IsolatedPluginBackend::Impl::~Impl() {
  try {
    shutdown();
  } catch (const std::exception&) {
    // A plugin whose destroy() fails cannot make a destructor throw; shutdown() reports it to callers that ask.
  }
  worker_.reset();
}

void IsolatedPluginBackend::Impl::wait_for_startup() {
  const auto started = Clock::now();
  auto limit = started + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(limits_.build_seconds));
  const bool deadline_first = limits_.deadline && *limits_.deadline < limit;
  if (deadline_first) limit = *limits_.deadline;
  std::uint32_t state;
  for (;;) {
    state = block_->header.startup.load(std::memory_order_acquire);
    if (state != static_cast<std::uint32_t>(pw::Startup::Starting) || ended_.load()) break;
    const auto now = Clock::now();
    if (now >= limit) {
      PluginFailureDetails d = base_details();
      d.kind = PluginFailureKind::Timeout;
      d.cause = "timeout";
      d.stage = "load";
      d.deadline_passed = deadline_first;
      d.detail = deadline_first ? std::string("the deadline passed")
                                : fmt::format("loading and create() took longer than {} s", limits_.build_seconds);
      fail(d, -1);
    }
    pw::futex_wait(&block_->header.startup, state, limit - now);
  }
  if (ended_.load()) throw_failure(-1);
  const pw::Header& h = block_->header;
  switch (static_cast<pw::Startup>(state)) {
    case pw::Startup::Ready:
      name_ = "plugin:" + bounded_string(h.plugin_name, sizeof h.plugin_name);
      flags_ = h.plugin_flags;
      batch_functions_ = h.batch_functions & (pw::kHasIntersectBatch | pw::kHasOccludedBatch);
      sandbox_ = bounded_string(h.sandbox, sizeof h.sandbox);
      if (h.sandbox_complete == 0) warn_once_about_sandbox(sandbox_);
      return;
    case pw::Startup::LoadFailed:
      // The in-process loader's own message, produced by the same code in the worker.
      throw InputError(path_, "", bounded_string(h.message, sizeof h.message));
    case pw::Startup::SetupFailed:
      throw std::runtime_error(fmt::format("{}: the plugin worker could not set itself up: {}", path_.string(),
                                           bounded_string(h.message, sizeof h.message)));
    case pw::Startup::Starting: break;
  }
  throw std::runtime_error(fmt::format("{}: the plugin worker answered with an unknown state {}", path_.string(), state));
}

BackendTraits IsolatedPluginBackend::Impl::traits() const {
  BackendTraits t;
  t.counts_traversal = (flags_ & TWINRAY_PLUGIN_COUNTS_TRAVERSAL) != 0;
  t.honours_ties = (flags_ & TWINRAY_PLUGIN_HONOURS_TIES) != 0;
  t.watertight = (flags_ & TWINRAY_PLUGIN_WATERTIGHT) != 0;
  return t;
}

// ---- channels ----------------------------------------------------------------------------------------------

std::size_t IsolatedPluginBackend::Impl::acquire_channel() {
  // Start where this thread last found a free channel: concurrent callers spread over the channels and each
  // keeps meeting the same (awake, cache-warm) worker thread.
  thread_local std::size_t hint = 0;
  for (;;) {
    const std::uint32_t seen = releases_.load(std::memory_order_acquire);
    for (std::size_t k = 0; k < pw::kChannels; ++k) {
      const std::size_t i = (hint + k) % pw::kChannels;
      if (!slots_[i].busy.exchange(true, std::memory_order_acquire)) {
        hint = i;
        return i;
      }
    }
    releases_.wait(seen, std::memory_order_acquire);  // all 16 in use: wait for a release
  }
}

void IsolatedPluginBackend::Impl::release_channel(std::size_t index) {
  {
    std::lock_guard lock(slots_[index].mutex);
    slots_[index].context = RequestContext{};
  }
  slots_[index].busy.store(false, std::memory_order_release);
  releases_.fetch_add(1, std::memory_order_release);
  releases_.notify_one();
}

void IsolatedPluginBackend::Impl::set_context(const Lease& lease, const RequestContext& context) {
  std::lock_guard lock(lease.slot().mutex);
  lease.slot().context = context;
}

void IsolatedPluginBackend::Impl::post(const Lease& lease) {
  pw::Channel& c = lease.channel();
  const std::uint32_t sequence = ++lease.slot().sequence;
  // seq_cst store, then seq_cst load of worker_sleeping: paired with the worker's store of worker_sleeping and
  // load of request, one of the two sides always sees the other, so a wake-up is never lost.
  c.request.store(sequence, std::memory_order_seq_cst);
  if (c.worker_sleeping.load(std::memory_order_seq_cst) != 0) pw::futex_wake_all(&c.request);
}

void IsolatedPluginBackend::Impl::round_trip(const Lease& lease, pw::Op op, std::uint32_t count,
                                             std::chrono::duration<double> per_call) {
  pw::Channel& c = lease.channel();
  c.op = op;
  c.count = count;
  c.instance = instance_;
  // The worker counts the rays of this request from 0 upward; it is idle now, so the word is ours to reset.
  c.current.store(0, std::memory_order_relaxed);
  post(lease);
  wait_for_answer(lease, lease.slot().sequence, per_call);
  check_answer(lease, op, count, lease.slot().context.stage);
}

void IsolatedPluginBackend::Impl::check_answer(const Lease& lease, pw::Op op, std::uint32_t count, Stage stage) {
  const pw::Channel& c = lease.channel();
  const pw::Op op_now = c.op;
  const std::uint32_t count_now = c.count;
  if (op_now != op || count_now != count)
    fail_corrupted(lease, stage,
                   fmt::format("the request was changed to op {}, {} rays (posted: op {}, {} rays)", static_cast<std::uint32_t>(op_now),
                               count_now, static_cast<std::uint32_t>(op), count));
  const pw::Status status = c.status;
  const bool batch = op == pw::Op::IntersectBatch || op == pw::Op::OccludedBatch;
  const bool query = batch || op == pw::Op::Intersect || op == pw::Op::Occluded;
  const bool possible = status == pw::Status::Ok || status == pw::Status::Exception || status == pw::Status::OutOfMemory ||
                        status == pw::Status::FpEnvironmentChanged ||
                        (batch && status == pw::Status::WriteOutOfBounds) ||
                        (!query && (status == pw::Status::BuildFailed || status == pw::Status::SetupFailed));
  if (!possible) fail_corrupted(lease, stage, fmt::format("status {}", static_cast<std::uint32_t>(status)));
  // The worker sets `current` to every ray's index in turn, so an answered batch ends on its last ray.
  const std::uint32_t at = c.current.load(std::memory_order_relaxed);
  if (query && status == pw::Status::Ok && count > 0 && at != count - 1)
    fail_corrupted(lease, stage, fmt::format("the answer of {} rays ends at ray {}", count, at));
  if (!query && status == pw::Status::Ok && c.build_stats.reported > 1)
    fail_corrupted(lease, stage, fmt::format("build_stats.reported {}", c.build_stats.reported));
}

bool IsolatedPluginBackend::Impl::found_of(const Lease& lease, Stage stage, std::uint32_t found) {
  if (found > 1) fail_corrupted(lease, stage, fmt::format("a result's found flag is {}", found));
  return found != 0;
}

void IsolatedPluginBackend::Impl::wait_for_answer(const Lease& lease, std::uint32_t sequence,
                                                  std::chrono::duration<double> per_call) {
  pw::Channel& c = lease.channel();
  const auto started = Clock::now();
  if (pw::spin_yielding([&] { return c.response.load(std::memory_order_acquire) == sequence; }, kCallerSpin)) return;
  // The per-call limit runs from the moment the worker starts a ray: a batch may take long in all, as long as
  // every single ray is quick. `current` is the worker's index of the ray in flight, which only ever grows
  // within a request (0, 1, ..., count - 1). Since it is the worker's word, and plugin code in the worker's
  // process can write it, it is trusted no further: an index that goes back or past the last ray is an answer
  // no worker gives (corrupted, at once), so a forged "progress" can at most step through the request's rays
  // once, each within the per-call limit, as a slow plugin would; the whole request is bounded by (rays) x
  // (per-call limit) and by the deadline.
  auto progress_at = started;
  std::uint32_t progress = c.current.load(std::memory_order_relaxed);
  const auto per_call_ticks = std::chrono::duration_cast<Clock::duration>(per_call);
  const auto request_limit = started + per_call_ticks * std::max<std::uint32_t>(1, lease.slot().context.count);
  for (;;) {
    const std::uint32_t seen = c.response.load(std::memory_order_seq_cst);
    if (seen == sequence) return;
    if (ended_.load()) throw_failure(static_cast<int>(lease.index()));
    // Until it answers, the worker's word holds the previous request's number: any other number is not its.
    if (seen != sequence - 1)
      fail_corrupted(lease, lease.slot().context.stage,
                     fmt::format("response sequence number {}, while request {} was awaited", seen, sequence));
    const auto now = Clock::now();
    const std::uint32_t at = c.current.load(std::memory_order_relaxed);
    if (at < progress || at >= std::max<std::uint32_t>(1, lease.slot().context.count))
      fail_corrupted(lease, lease.slot().context.stage,
                     fmt::format("the index of the ray in flight went from {} to {} in a request of {} rays", progress, at,
                                 lease.slot().context.count));
    if (at != progress) {
      progress = at;
      progress_at = now;
    }
    auto limit = std::min(progress_at + per_call_ticks, request_limit);
    const bool deadline_first = limits_.deadline && *limits_.deadline < limit;
    if (deadline_first) limit = *limits_.deadline;
    if (now >= limit)
      fail_timeout(lease, lease.slot().context.stage, deadline_first, std::chrono::duration<double>(now - progress_at).count(),
                   per_call);
    c.parent_sleeping.store(1, std::memory_order_seq_cst);
    if (c.response.load(std::memory_order_seq_cst) == seen && !ended_.load()) pw::futex_wait(&c.response, seen, limit - now);
    c.parent_sleeping.store(0, std::memory_order_relaxed);
  }
}

// ---- failures ----------------------------------------------------------------------------------------------

PluginFailureDetails IsolatedPluginBackend::Impl::base_details() const {
  PluginFailureDetails d;
  d.plugin = name_.empty() ? path_.string() : fmt::format("{} ({})", name_, path_.string());
  return d;
}

void IsolatedPluginBackend::Impl::record_failure(PluginFailureDetails details, int channel) {
  std::lock_guard lock(failure_mutex_);
  if (!failure_) {
    failure_ = std::move(details);
    failure_channel_ = channel;
  }
  ended_.store(true);
}

void IsolatedPluginBackend::Impl::end_worker() {
  ended_.store(true);
  if (!worker_) return;
  worker_->kill();
  worker_->wait_for_exit(kReapWait);
}

void IsolatedPluginBackend::Impl::fail(PluginFailureDetails details, int channel) {
  record_failure(std::move(details), channel);
  end_worker();
  throw_failure(channel);
}

void IsolatedPluginBackend::Impl::throw_failure(int channel) const {
  failure_reported_.store(true);
  throw failure_for(channel);
}

PluginFailure IsolatedPluginBackend::Impl::failure_for(int channel) const {
  PluginFailureDetails d;
  {
    std::lock_guard lock(failure_mutex_);
    if (!failure_) {
      // Ended without a failure: shut down, or killed while shutting down.
      d = base_details();
      d.cause = "exit";
      d.detail = "the plugin worker has been shut down";
      return PluginFailure(d);
    }
    d = *failure_;
    // ray_index is an index into the caller's own span: only the caller whose ray it was gets it.
    if (channel < 0 || channel != failure_channel_) d.ray_index.reset();
  }
  if (worker_) d.output = worker_->output();
  return PluginFailure(d);
}

void IsolatedPluginBackend::Impl::throw_if_failed() const {
  if (!ended_.load()) return;
  PluginFailure first = failure_for(-1);
  PluginFailureDetails d = first;
  d.ray_index.reset();
  d.detail = d.detail.empty() ? std::string("the worker ended in an earlier call; make a new instance")
                              : d.detail + "; the worker ended in an earlier call; make a new instance";
  failure_reported_.store(true);
  throw PluginFailure(d);
}

std::optional<PluginFailure> IsolatedPluginBackend::Impl::failure() const {
  {
    std::lock_guard lock(failure_mutex_);
    if (!failure_) return std::nullopt;
  }
  return failure_for(-1);
}

void IsolatedPluginBackend::Impl::attribute_ray(const RequestContext& context, std::uint32_t request_index,
                                                PluginFailureDetails& d, bool whole_call) const {
  if (request_index >= context.count) return;  // the worker's word, so checked
  const std::size_t index = context.source != nullptr ? context.source[request_index] : request_index;
  if (index >= context.rays.size()) return;
  d.ray_index = index;
  d.ray = context.rays[index];
  if (whole_call && (context.stage == Stage::IntersectBatch || context.stage == Stage::OccludedBatch)) {
    // One call of the plugin's batch function was under way: the worker knows its first ray only.
    const std::uint32_t calls_rays = std::min<std::uint32_t>(context.count - request_index,
                                                             static_cast<std::uint32_t>(pw::kBatchCallRays));
    const std::string where = fmt::format("in a call of {} rays from ray {} (the batch function gives no ray of its own)",
                                          calls_rays, index);
    d.detail = d.detail.empty() ? where : where + "; " + d.detail;
  }
}

void IsolatedPluginBackend::Impl::fail_timeout(const Lease& lease, Stage stage, bool deadline_passed,
                                               double call_seconds, std::chrono::duration<double> per_call) {
  PluginFailureDetails d = base_details();
  d.kind = PluginFailureKind::Timeout;
  d.cause = "timeout";
  d.stage = stage_name(stage);
  {
    std::lock_guard lock(lease.slot().mutex);
    attribute_ray(lease.slot().context, lease.channel().current.load(), d);
  }
  d.deadline_passed = deadline_passed;
  d.call_seconds = call_seconds;
  d.detail = deadline_passed ? std::string("the deadline passed")
                             : fmt::format("one call took longer than {} s", per_call.count());
  fail(d, static_cast<int>(lease.index()));
}

void IsolatedPluginBackend::Impl::fail_from_status(const Lease& lease, Stage stage) {
  const pw::Channel& c = lease.channel();
  PluginFailureDetails d = base_details();
  d.kind = PluginFailureKind::Crash;
  d.stage = stage_name(stage);
  const std::string message = bounded_string(c.message, sizeof c.message);
  switch (c.status) {
    case pw::Status::Exception:
      d.cause = "exception";
      d.detail = message;
      break;
    case pw::Status::OutOfMemory:
      d.cause = "out-of-memory";
      d.detail = message.empty() ? "std::bad_alloc" : message;
      break;
    case pw::Status::FpEnvironmentChanged:
      // The worker put the bits back, but the plugin broke the ABI's promise (docs/plugin-abi.md, "Lifecycle
      // and threading", item 5): in process it would have changed the host's arithmetic.
      d.kind = PluginFailureKind::ContractViolation;
      d.cause = "fp-environment";
      d.detail = message;
      break;
    case pw::Status::WriteOutOfBounds:
      d.kind = PluginFailureKind::ContractViolation;
      d.cause = "out-of-bounds-write";
      d.detail = message;
      break;
    case pw::Status::SetupFailed:
      end_worker();
      throw std::runtime_error(fmt::format("{}: the plugin worker failed in {}: {}", d.plugin, d.stage,
                                           message.empty() ? "no message given" : message));
    default: fail_corrupted(lease, stage, fmt::format("status {}", static_cast<std::uint32_t>(c.status)));
  }
  {
    std::lock_guard lock(lease.slot().mutex);
    attribute_ray(lease.slot().context, c.current.load(), d);
  }
  fail(d, static_cast<int>(lease.index()));
}

void IsolatedPluginBackend::Impl::fail_corrupted(const Lease& lease, Stage stage, const std::string& what) {
  PluginFailureDetails d = base_details();
  d.kind = PluginFailureKind::Crash;
  d.cause = "corrupted";
  d.stage = stage_name(stage);
  d.detail = "it holds an answer the worker cannot give: " + what;
  fail(d, static_cast<int>(lease.index()));
}

void IsolatedPluginBackend::Impl::fail_bad_hit(const Lease& lease, Stage stage, std::size_t request_index,
                                               const twinray_hit& h) {
  PluginFailureDetails d = base_details();
  d.kind = PluginFailureKind::ContractViolation;
  d.cause = "bad-hit";
  d.stage = stage_name(stage);
  {
    std::lock_guard lock(lease.slot().mutex);
    attribute_ray(lease.slot().context, static_cast<std::uint32_t>(request_index), d, false);
  }
  d.detail = fmt::format("reported a hit on geom_id {}, prim_id {}, which the scene does not have", h.geom_id, h.prim_id);
  fail(d, static_cast<int>(lease.index()));
}

// The process CPU clock of the worker (clock_getcpuclockid: every thread's time, readable by the parent without
// privileges). Read only while the worker runs (not yet reaped), so the pid belongs to no other process.
std::optional<double> IsolatedPluginBackend::Impl::worker_cpu_seconds() const {
  if (!worker_ || !worker_->running()) return std::nullopt;
  clockid_t clock;
  if (clock_getcpuclockid(worker_->pid(), &clock) != 0) return std::nullopt;
  timespec ts{};
  if (clock_gettime(clock, &ts) != 0) return std::nullopt;
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

// Runs on the monitor thread as soon as the worker has been reaped.
void IsolatedPluginBackend::Impl::on_worker_exit(const WorkerTermination& t) {
  const bool clean = clean_exit_expected_.load() && t.exited && t.exit_code == 0 &&
                     block_->header.crash.what.load() == pw::kCrashNone;
  if (!clean) {
    int channel = -1;
    PluginFailureDetails d = classify_death(t, channel);
    record_failure(std::move(d), channel);
  }
  ended_.store(true);
  // Wake every caller that waits for an answer, and one waiting for the worker to start. The words change
  // before the wake, so a caller that read the old value and is just about to sleep on it returns at once
  // (futex_wait compares first) and then sees ended_.
  block_->header.startup.fetch_add(kDeathBump);
  pw::futex_wake_all(&block_->header.startup);
  for (pw::Channel& c : block_->channels) {
    c.response.fetch_add(kDeathBump);
    pw::futex_wake_all(&c.response);
  }
}

PluginFailureDetails IsolatedPluginBackend::Impl::classify_death(const WorkerTermination& t, int& channel) const {
  PluginFailureDetails d = base_details();
  d.kind = PluginFailureKind::Crash;
  const pw::CrashRecord& record = block_->header.crash;
  const std::uint32_t what = record.what.load();
  const std::int32_t thread = record.thread.load();

  // Whose ray: the thread the signal handler (or exit) ran on, else the only channel running plugin code.
  channel = -1;
  if (what != pw::kCrashNone && thread >= 0 && static_cast<std::size_t>(thread) < pw::kChannels) channel = thread;
  if (channel < 0) {
    int running = 0;
    for (std::size_t i = 0; i < pw::kChannels; ++i)
      if (block_->channels[i].in_plugin.load() != 0) {
        channel = static_cast<int>(i);
        ++running;
      }
    if (running != 1) channel = -1;
  }
  const bool loading = block_->header.loading.load() != 0 ||
                       (block_->header.startup.load() & ~kDeathBump) == static_cast<std::uint32_t>(pw::Startup::Starting);
  if (channel >= 0) {
    std::lock_guard lock(slots_[static_cast<std::size_t>(channel)].mutex);
    const RequestContext& context = slots_[static_cast<std::size_t>(channel)].context;
    if (context.active) {
      d.stage = stage_name(context.stage);
      if (is_query(context.stage))
        attribute_ray(context, block_->channels[static_cast<std::size_t>(channel)].current.load(), d);
    }
  }
  if (d.stage.empty() && loading) d.stage = "load";
  if (d.stage.empty()) {
    for (const ChannelSlot& s : slots_) {
      std::lock_guard lock(s.mutex);
      if (s.context.active) {
        d.stage = stage_name(s.context.stage);
        break;
      }
    }
  }
  if (d.stage.empty()) d.detail = "while no call was in progress (a thread of the plugin?)";

  if (t.exited) {
    // exit() in a call in which an allocation had failed is how some plugins give up on memory.
    d.cause = what == pw::kCrashExit && record.allocation_failed.load() != 0 ? "out-of-memory" : "exit";
    d.exit_code = t.exit_code;
    return d;
  }
  d.signal_name = signal_name(t.signal);
  const bool handled_signal = what == pw::kCrashSignal && record.signal.load() == t.signal;
  if (t.signal == SIGSYS && handled_signal && record.syscall.load() >= 0) {
    d.cause = "sandbox";
    d.syscall = syscall_name(record.syscall.load());
  } else if (handled_signal && record.allocation_failed.load() != 0) {
    d.cause = "out-of-memory";
  } else if (t.signal == SIGABRT) {
    d.cause = "abort";
  } else {
    d.cause = "signal";
    if (t.signal == SIGKILL && !t.killed_by_twinray)
      d.detail = "SIGKILL not sent by twinray: the kernel's out-of-memory killer, or another process";
  }
  return d;
}

// ---- build and queries ---------------------------------------------------------------------------------------

void IsolatedPluginBackend::Impl::build(const SceneGeometry& geometry) {
  throw_if_failed();
  if (built_[instance_]) throw std::logic_error(name_ + ": build() called twice (the ABI allows one build per instance)");
  built_[instance_] = true;
  const auto start = Clock::now();
  primitives_[instance_] = PrimitiveIndex(geometry);

  // The scene goes after the control block, at a page boundary so the worker can map exactly that part.
  const std::size_t offset = round_up(control_file_.size(), page_size());
  const std::size_t bytes = std::max<std::size_t>(geometry_blob_bytes(geometry), 1);
  control_file_.grow(offset + round_up(bytes, page_size()));
  {
    // twinray's own mapping is only for writing; the worker keeps its read-only one until destroy.
    const SharedMapping blob(control_file_, offset, bytes);
    write_geometry_blob(geometry, blob.data());
  }

  Lease lease(*this);
  pw::Channel& c = lease.channel();
  c.geometry_offset = offset;
  c.geometry_bytes = bytes;
  set_context(lease, RequestContext{true, Stage::Build, {}, nullptr, 0});
  round_trip(lease, pw::Op::Build, 0, std::chrono::duration<double>(limits_.build_seconds));
  switch (c.status) {
    case pw::Status::Ok: break;
    case pw::Status::BuildFailed:
      // As the in-process backend words it: the plugin declined, it did not crash.
      throw PluginBuildError(name_ + " (" + path_.string() + "): build failed: " +
                               [&] {
                                 const std::string m = bounded_string(c.message, sizeof c.message);
                                 return m.empty() ? std::string("no message given") : m;
                               }());
    default: fail_from_status(lease, Stage::Build);
  }

  BuildStats& built = stats_[instance_];
  built = BuildStats{};
  built.build_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  built.triangles = geometry.triangle_count();
  built.spheres = geometry.sphere_count();
  built.built_triangles = geometry.has_triangles();
  built.built_spheres = geometry.has_spheres();
  const pw::BuildStatsWire wire = c.build_stats;
  if (wire.reported != 0) {
    built.memory_bytes = wire.memory_bytes;
    built.nodes = wire.nodes;
    built.leaves = wire.leaves;
    built.max_depth = wire.max_depth;
    built.sah_cost = wire.sah_cost;
  }
}

namespace {
void add_stats(QueryStats* stats, std::size_t queries, std::uint64_t nodes, std::uint64_t primitives) {
  if (stats == nullptr) return;
  stats->queries += queries;
  stats->nodes_visited += nodes;
  stats->primitives_tested += primitives;
}
}  // namespace

bool IsolatedPluginBackend::Impl::intersect(const Ray& ray, Hit& hit, QueryStats* stats) {
  throw_if_failed();
  hit = Hit{};
  if (!is_valid_ray(ray)) {  // a miss, never sent (core/geometry/ray.h)
    add_stats(stats, 1, 0, 0);
    return false;
  }
  Lease lease(*this);
  pw::Channel& c = lease.channel();
  c.rays[0] = to_plugin_ray(ray);
  set_context(lease, RequestContext{true, Stage::Intersect, std::span<const Ray>(&ray, 1), nullptr, 1});
  round_trip(lease, pw::Op::Intersect, 1, std::chrono::duration<double>(limits_.query_seconds));
  if (c.status != pw::Status::Ok) fail_from_status(lease, Stage::Intersect);
  const pw::RayResult r = c.results[0];  // one copy: what is checked is what is used
  add_stats(stats, 1, c.nodes_visited, c.primitives_tested);
  if (!found_of(lease, Stage::Intersect, r.found)) return false;
  if (!primitives_[instance_].exists(r.hit.geom_id, r.hit.prim_id)) fail_bad_hit(lease, Stage::Intersect, 0, r.hit);
  hit = from_plugin_hit(r.hit);
  return true;
}

bool IsolatedPluginBackend::Impl::occluded(const Ray& ray, QueryStats* stats) {
  throw_if_failed();
  if (!is_valid_ray(ray)) {
    add_stats(stats, 1, 0, 0);
    return false;
  }
  Lease lease(*this);
  pw::Channel& c = lease.channel();
  c.rays[0] = to_plugin_ray(ray);
  set_context(lease, RequestContext{true, Stage::Occluded, std::span<const Ray>(&ray, 1), nullptr, 1});
  round_trip(lease, pw::Op::Occluded, 1, std::chrono::duration<double>(limits_.query_seconds));
  if (c.status != pw::Status::Ok) fail_from_status(lease, Stage::Occluded);
  const std::uint32_t found = c.results[0].found;
  add_stats(stats, 1, c.nodes_visited, c.primitives_tested);
  return found_of(lease, Stage::Occluded, found);
}

// A batch runs on one channel, in chunks of up to kChunkRays valid rays (invalid rays are misses and never
// sent), like the in-process backend runs it on the calling thread.
template <typename Miss, typename Take>
void IsolatedPluginBackend::Impl::query_in_chunks(std::span<const Ray> rays, pw::Op op, Stage stage, QueryStats* stats,
                                                  Miss miss, Take take) {
  throw_if_failed();
  std::uint64_t nodes = 0, primitives = 0;
  Lease lease(*this);
  pw::Channel& c = lease.channel();
  std::array<std::size_t, pw::kChunkRays>& source = lease.slot().source;
  std::size_t i = 0;
  while (i < rays.size()) {
    std::uint32_t n = 0;
    for (; i < rays.size() && n < pw::kChunkRays; ++i) {
      miss(i);
      if (!is_valid_ray(rays[i])) continue;
      c.rays[n] = to_plugin_ray(rays[i]);
      source[n++] = i;
    }
    if (n == 0) continue;
    set_context(lease, RequestContext{true, stage, rays, source.data(), n});
    round_trip(lease, op, n, std::chrono::duration<double>(limits_.query_seconds));
    if (c.status != pw::Status::Ok) fail_from_status(lease, stage);
    nodes += c.nodes_visited;
    primitives += c.primitives_tested;
    // Each result is copied out of the shared memory once: the plugin's process could still write to it
    // between a check and a use.
    for (std::uint32_t k = 0; k < n; ++k) take(lease, k, source[k], pw::RayResult(c.results[k]));
  }
  add_stats(stats, rays.size(), nodes, primitives);
}

void IsolatedPluginBackend::Impl::intersect(std::span<const Ray> rays, std::span<Hit> hits, QueryStats* stats) {
  assert(rays.size() == hits.size());
  const bool batch = batch_path_ == BatchPath::PluginBatch && has_intersect_batch();
  const Stage stage = batch ? Stage::IntersectBatch : Stage::Intersect;
  query_in_chunks(
      rays, batch ? pw::Op::IntersectBatch : pw::Op::Intersect, stage, stats, [&](std::size_t i) { hits[i] = Hit{}; },
      [&](const Lease& lease, std::uint32_t k, std::size_t i, pw::RayResult r) {
        if (!found_of(lease, stage, r.found)) return;
        if (!primitives_[instance_].exists(r.hit.geom_id, r.hit.prim_id)) fail_bad_hit(lease, stage, k, r.hit);
        hits[i] = from_plugin_hit(r.hit);
      });
}

void IsolatedPluginBackend::Impl::occluded(std::span<const Ray> rays, std::span<std::uint8_t> occluded, QueryStats* stats) {
  assert(rays.size() == occluded.size());
  const bool batch = batch_path_ == BatchPath::PluginBatch && has_occluded_batch();
  const Stage stage = batch ? Stage::OccludedBatch : Stage::Occluded;
  query_in_chunks(
      rays, batch ? pw::Op::OccludedBatch : pw::Op::Occluded, stage, stats, [&](std::size_t i) { occluded[i] = 0; },
      [&](const Lease& lease, std::uint32_t, std::size_t i, pw::RayResult r) {
        occluded[i] = found_of(lease, stage, r.found) ? 1 : 0;
      });
}

void IsolatedPluginBackend::Impl::shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  if (ended_.load() || !worker_ || !worker_->running()) {
    ended_.store(true);
    // The worker died while no call of ours was waiting (a thread of the plugin crashed after the last
    // answer): no caller has heard of it, so the end of the instance reports it.
    if (worker_) worker_->wait_for_exit(kReapWait);
    if (!failure_reported_.load() && failure()) {
      failure_reported_.store(true);
      throw *failure();
    }
    return;
  }
  {
    Lease lease(*this);  // no call is in flight (Backend contract), so this does not wait
    pw::Channel& c = lease.channel();
    c.op = pw::Op::Destroy;
    c.count = 0;
    set_context(lease, RequestContext{true, Stage::Destroy, {}, nullptr, 0});
    clean_exit_expected_.store(true);
    post(lease);
    // The worker answers a destroy by exiting; its exit status is the answer. The plugin's part (destroy(), its
    // atexit handlers and static destructors) has one call's limit; the process's own end after that (the C
    // library's, the kernel's unmapping of what may be gigabytes) a generous bound of its own.
    const auto per_call = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(limits_.query_seconds));
    const auto handlers_limit = Clock::now() + per_call;
    std::atomic<std::uint32_t>& done = block_->header.crash.exit_handlers_done;
    while (done.load() == 0 && worker_->running() && Clock::now() < handlers_limit)
      pw::futex_wait(&done, 0, std::min<Clock::duration>(handlers_limit - Clock::now(), std::chrono::milliseconds(10)));
    const bool handlers_ran = done.load() != 0 || !worker_->running();
    if (!handlers_ran || !worker_->wait_for_exit(per_call + kTeardownWait)) {
      PluginFailureDetails d = base_details();
      d.kind = PluginFailureKind::Timeout;
      d.cause = "timeout";
      d.stage = "destroy";
      d.detail = handlers_ran
                     ? fmt::format("the worker did not end within {} s of the plugin's exit handlers (a destructor of "
                                   "the library that never returns?)",
                                   limits_.query_seconds + std::chrono::duration<double>(kTeardownWait).count())
                     : fmt::format("destroy() and the plugin's exit handlers and static destructors took longer than {} s",
                                   limits_.query_seconds);
      record_failure(d, static_cast<int>(lease.index()));
      end_worker();
    }
  }
  ended_.store(true);
  if (failure()) {
    failure_reported_.store(true);
    throw *failure();
  }
}

// ---- the public class ----------------------------------------------------------------------------------------

IsolatedPluginBackend::IsolatedPluginBackend(const std::filesystem::path& so, const PluginLimits& limits)
    : impl_(std::make_unique<Impl>(so, limits)) {}
IsolatedPluginBackend::~IsolatedPluginBackend() = default;

std::string_view IsolatedPluginBackend::name() const { return impl_->name(); }
BackendTraits IsolatedPluginBackend::traits() const { return impl_->traits(); }
void IsolatedPluginBackend::build(const SceneGeometry& geometry) { impl_->build(geometry); }
BuildStats IsolatedPluginBackend::build_stats() const { return impl_->build_stats(); }
bool IsolatedPluginBackend::intersect(const Ray& ray, Hit& hit, QueryStats* stats) const {
  return impl_->intersect(ray, hit, stats);
}
bool IsolatedPluginBackend::occluded(const Ray& ray, QueryStats* stats) const { return impl_->occluded(ray, stats); }
void IsolatedPluginBackend::intersect(std::span<const Ray> rays, std::span<Hit> hits, QueryStats* stats) const {
  impl_->intersect(rays, hits, stats);
}
void IsolatedPluginBackend::occluded(std::span<const Ray> rays, std::span<std::uint8_t> occluded, QueryStats* stats) const {
  impl_->occluded(rays, occluded, stats);
}
void IsolatedPluginBackend::set_deadline(std::optional<std::chrono::steady_clock::time_point> deadline) {
  impl_->set_deadline(deadline);
}
const PluginLimits& IsolatedPluginBackend::limits() const { return impl_->limits(); }
void IsolatedPluginBackend::set_batch_path(BatchPath path) { impl_->set_batch_path(path); }
BatchPath IsolatedPluginBackend::batch_path() const { return impl_->batch_path(); }
bool IsolatedPluginBackend::has_intersect_batch() const { return impl_->has_intersect_batch(); }
bool IsolatedPluginBackend::has_occluded_batch() const { return impl_->has_occluded_batch(); }
void IsolatedPluginBackend::use_instance(std::size_t index) { impl_->use_instance(index); }
std::string IsolatedPluginBackend::captured_output() const { return impl_->captured_output(); }
std::optional<double> IsolatedPluginBackend::worker_cpu_seconds() const { return impl_->worker_cpu_seconds(); }
std::optional<PluginFailure> IsolatedPluginBackend::failure() const { return impl_->failure(); }
std::string IsolatedPluginBackend::sandbox_description() const { return impl_->sandbox_description(); }
void IsolatedPluginBackend::shutdown() { impl_->shutdown(); }

std::unique_ptr<IsolatedPluginBackend> make_isolated_plugin_backend(const std::filesystem::path& so,
                                                                    const PluginLimits& limits) {
  return std::make_unique<IsolatedPluginBackend>(so, limits);
}

}  // namespace twinray
