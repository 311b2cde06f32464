#pragma once
// The shared memory between twinray and its plugin worker process (backends/plugin/worker): its layout, the
// request codes and the handshake. Both sides include this header; nothing else crosses between them except
// the worker's stdout and stderr (a pipe the parent drains) and its exit status.
//
// One memfd holds, from offset 0, a ControlBlock: a Header (limits in, load result and crash record out) and
// kChannels Channels, one per worker query thread. At build time the parent grows the memfd and appends the
// scene (GeometryBlob) at a page-aligned offset; the worker maps that part read-only and keeps it until the
// plugin is destroyed, as the ABI promises.
//
// Handshake on a channel (futexes on words of the shared mapping, so they work across the two processes):
//   parent: write op and rays, request = n (release), wake the worker if it sleeps
//   worker: sees request == n, calls the plugin, writes results, response = n (release), wakes the parent
// Each side spins briefly before sleeping on the word (see futex.h), so back-to-back single-ray calls need no
// system call at all. The parent never trusts what the worker wrote: counts, indices and hits are checked, and
// every wait has a timeout (PluginLimits) so a worker that stops answering cannot hang twinray.

#include "backends/plugin/twinray_plugin.h"

#include <atomic>
#include <cstddef>
#include <cstdint>

namespace twinray::plugin_worker {

inline constexpr std::uint32_t kMagic = 0x7477726bu;  // "twrk"
inline constexpr std::uint32_t kProtocolVersion = 5;

// File descriptors of the worker: 0 /dev/null, 1 and 2 the output pipe, kControlFd the memfd, kLifelineFd the
// read end of a pipe whose write end only the parent holds (EOF: the parent is gone, the worker exits).
inline constexpr int kControlFd = 3;
inline constexpr int kLifelineFd = 4;

// Query threads in the worker, each serving one channel; a parent thread holds one channel per call.
inline constexpr std::size_t kChannels = 16;
// Plugin instances one worker can hold: the one create() made at start (0) and a second one (1), created by
// the first Build request addressed to it. The grader's two-instances check builds both on different scenes
// and queries each: the ABI promises that instances in one process are independent (docs/plugin-abi.md).
inline constexpr std::uint32_t kInstances = 2;
// Rays per round trip of a batch call: 4096 rays and results are 300 KiB, so the handshake (a few
// microseconds) is amortised to nothing while a channel stays a small part of the worker's memory.
inline constexpr std::size_t kChunkRays = 4096;

// Rays per call of the plugin's own batch function (intersect_batch, occluded_batch): a request of up to
// kChunkRays rays is handed over in calls of at most this many, as the in-process backend hands them over
// (plugin_backend.cpp), so a plugin sees the same batch sizes in and out of isolation. It is also what one
// "call" is for the per-call time limit and what a crash is pinned to: the worker sets `current` to the first
// ray of each batch call (a batch function gives no progress of its own), and to the request's last ray when
// the last call has returned.
inline constexpr std::size_t kBatchCallRays = 256;

// Intersect / Occluded: one intersect1 / occluded1 call per ray. IntersectBatch / OccludedBatch: the plugin's
// intersect_batch / occluded_batch (twinray sends them only to a plugin that has them: Header::batch_functions).
enum class Op : std::uint32_t {
  None = 0,
  Build = 1,
  Intersect = 2,
  Occluded = 3,
  Destroy = 4,
  IntersectBatch = 5,
  OccludedBatch = 6,
};

// Header::batch_functions: which optional batch entry points the plugin's table has.
inline constexpr std::uint32_t kHasIntersectBatch = 1u;
inline constexpr std::uint32_t kHasOccludedBatch = 2u;

enum class Status : std::uint32_t {
  Ok = 0,
  BuildFailed = 1,   // build() returned TWINRAY_ERROR; message holds the plugin's text
  Exception = 2,     // a C++ exception escaped from plugin code; message holds what()
  OutOfMemory = 3,   // std::bad_alloc escaped from plugin code
  SetupFailed = 4,   // the worker could not do its own part (map the scene, install the filter); message says why
  // Contract violations the worker sees (protocol v5); message says what:
  FpEnvironmentChanged = 5,  // the call returned with other floating-point control bits (fp_environment.h)
  WriteOutOfBounds = 6,      // a batch call wrote past the answers it was given (the worker's guard bytes)
};

// Header::startup, a futex word the parent waits on after spawning the worker.
enum class Startup : std::uint32_t { Starting = 0, Ready = 1, LoadFailed = 2, SetupFailed = 3 };

// CrashRecord::what
inline constexpr std::uint32_t kCrashNone = 0;
inline constexpr std::uint32_t kCrashSignal = 1;  // a fatal signal's handler ran
inline constexpr std::uint32_t kCrashExit = 2;    // exit() was called (an atexit handler ran)

// CrashRecord::thread: the channel whose thread it was, or one of these.
inline constexpr std::int32_t kMainThread = -1;    // the worker's main thread (loading, create)
inline constexpr std::int32_t kPluginThread = -2;  // a thread the plugin created

// Written by the worker's fatal-signal handler and atexit handler (async-signal-safe stores only); the parent
// reads it after the worker has died.
struct CrashRecord {
  std::atomic<std::uint32_t> what{kCrashNone};
  std::atomic<std::int32_t> signal{0};
  std::atomic<std::int32_t> thread{kMainThread};
  std::atomic<std::int32_t> syscall{-1};              // SIGSYS from the seccomp filter: the system call number
  std::atomic<std::uint32_t> allocation_failed{0};    // errno was ENOMEM when the signal came (see worker)
  // 1 once the worker's own exit after destroy has run every atexit handler and static destructor of the plugin
  // (the recorder's hook runs last): what is left is the C library's and the kernel's teardown of the process,
  // which for a plugin that used gigabytes can take seconds on a busy machine and is not the plugin's time.
  std::atomic<std::uint32_t> exit_handlers_done{0};
};

struct Header {
  // Written by the parent before the worker starts.
  std::uint32_t magic = kMagic;
  std::uint32_t version = kProtocolVersion;
  std::uint64_t control_bytes = 0;  // size of the ControlBlock mapping
  std::uint64_t memory_bytes = 0;   // PluginLimits::memory_bytes: RLIMIT_AS, or ASan's malloc limit

  // Written by the worker.
  std::atomic<std::uint32_t> startup{static_cast<std::uint32_t>(Startup::Starting)};
  std::atomic<std::uint32_t> loading{0};  // 1 while the main thread runs plugin code (dlopen, create)
  std::uint32_t plugin_flags = 0;
  std::uint32_t batch_functions = 0;  // kHasIntersectBatch | kHasOccludedBatch
  char plugin_name[128] = {};
  char message[2048] = {};   // why loading or setting up failed
  char sandbox[512] = {};    // which layers of the sandbox are in place, in words
  std::uint32_t sandbox_complete = 0;  // 1: Landlock and seccomp are both in force
  CrashRecord crash;
};

// One result of a query: the hit (closest-hit calls) and the plugin's return value.
struct RayResult {
  twinray_hit hit;
  // intersect1's or occluded1's return value, normalised to 0 or 1; for the batch ops, whether intersect_batch's
  // hit has a geom_id other than TWINRAY_INVALID_ID, or occluded_batch's byte is not 0 (as plugin_backend.cpp
  // reads them)
  std::uint32_t found;
};

struct BuildStatsWire {
  std::uint32_t reported = 0;  // the plugin has build_stats
  std::uint64_t memory_bytes = 0, nodes = 0, leaves = 0, max_depth = 0;
  double sah_cost = 0.0;
};

struct alignas(64) Channel {
  // Parent -> worker. The two handshake words sit on their own cache lines: each is written by one side only.
  std::atomic<std::uint32_t> request{0};
  std::atomic<std::uint32_t> worker_sleeping{0};
  alignas(64) std::atomic<std::uint32_t> response{0};
  std::atomic<std::uint32_t> parent_sleeping{0};

  alignas(64) Op op = Op::None;
  std::uint32_t count = 0;            // rays in this request
  std::uint32_t instance = 0;         // which plugin instance the request is for (< kInstances)
  std::uint64_t geometry_offset = 0;  // Build: where the GeometryBlob starts in the memfd (page aligned)
  std::uint64_t geometry_bytes = 0;

  // Where the worker is, for attributing a crash or a timeout to one ray.
  std::atomic<std::uint32_t> in_plugin{0};  // 1 while plugin code runs on this channel's thread
  std::atomic<std::uint32_t> current{0};    // index in this request of the ray being traced

  // Answer.
  Status status = Status::Ok;
  std::uint64_t nodes_visited = 0;
  std::uint64_t primitives_tested = 0;
  BuildStatsWire build_stats;
  char message[1024] = {};

  twinray_ray rays[kChunkRays];
  RayResult results[kChunkRays];
};

struct ControlBlock {
  Header header;
  Channel channels[kChannels];
};

static_assert(std::atomic<std::uint32_t>::is_always_lock_free && std::atomic<std::int32_t>::is_always_lock_free,
              "atomics in memory shared between processes must be lock-free (address-free)");

// The scene, as the parent lays it out at Channel::geometry_offset. Offsets are from the start of the blob;
// every array starts on a 64-byte boundary and the positions are followed by at least 16 readable bytes (the
// ABI promises 4, for 16-byte SIMD loads of the last vertex).
struct GeometryBlobHeader {
  std::uint64_t mesh_count = 0;
  std::uint64_t sphere_count = 0;
  std::uint32_t geom_id_end = 0;
  std::uint32_t reserved = 0;
  // Followed by MeshRecord[mesh_count] and twinray_sphere[sphere_count], then the arrays.
};

struct MeshRecord {
  std::uint32_t geom_id = 0;
  std::uint32_t reserved = 0;
  std::uint64_t vertex_count = 0;
  std::uint64_t positions_offset = 0;
  std::uint64_t triangle_count = 0;
  std::uint64_t indices_offset = 0;
};

}  // namespace twinray::plugin_worker
