#include "backends/plugin/worker/query_server.h"

#include "backends/plugin/futex.h"
#include "backends/plugin/worker/crash_recorder.h"
#include "backends/plugin/worker/fp_environment.h"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <thread>

namespace twinray::plugin_worker {

namespace {

// How long a query thread waits for the next request (yielding, futex.h) before it sleeps: twinray's renderer
// sends its next ray within microseconds, and catching it awake saves both sides a futex wake-up.
constexpr auto kWorkerSpin = std::chrono::microseconds(50);

void copy_message(char* destination, std::size_t capacity, const char* text) {
  const std::size_t n = strnlen(text, capacity - 1);
  std::memmove(destination, text, n);
  destination[n] = '\0';
}

twinray_hit miss() {
  twinray_hit h{};
  h.geom_id = TWINRAY_INVALID_ID;
  h.prim_id = TWINRAY_INVALID_ID;
  return h;
}

// Runs plugin code, turning an escaping C++ exception into the channel's status (a plugin in C++ that throws
// breaks the C ABI's rule; unwinding through C frames would end in std::terminate, which is an abort).
template <typename F>
void guarded(Channel& c, F&& call) {
  c.in_plugin.store(1, std::memory_order_relaxed);
  const std::uint32_t fp_before = fp_control_bits();
  try {
    call();
  } catch (const std::bad_alloc& e) {
    c.status = Status::OutOfMemory;
    copy_message(c.message, sizeof c.message, e.what());
  } catch (const std::exception& e) {
    c.status = Status::Exception;
    copy_message(c.message, sizeof c.message, e.what());
  } catch (...) {
    c.status = Status::Exception;
    copy_message(c.message, sizeof c.message, "an exception not derived from std::exception");
  }
  c.in_plugin.store(0, std::memory_order_relaxed);
  const std::uint32_t fp_after = fp_control_bits();
  if (fp_after != fp_before) {
    restore_fp_control_bits(fp_before);
    if (c.status == Status::Ok) {
      c.status = Status::FpEnvironmentChanged;
      copy_message(c.message, sizeof c.message, describe_fp_change(fp_before, fp_after).c_str());
    }
  }
}

// Guard entries after the answers a batch call is given: filled with kGuardByte before the call and compared
// after it, so a plugin that stores past its `count` answers (a last group of a SIMD width written whole) is
// caught where it would otherwise write into unused room or the next call's answers unseen. As many as a
// 16-lane store can overrun.
constexpr std::size_t kGuardHits = 16;
constexpr std::size_t kGuardFlags = 64;
constexpr unsigned char kGuardByte = 0xA5;

// The first guard byte that is no longer kGuardByte, or -1.
std::ptrdiff_t first_overwritten(const void* guard, std::size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(guard);
  for (std::size_t i = 0; i < bytes; ++i)
    if (p[i] != kGuardByte) return static_cast<std::ptrdiff_t>(i);
  return -1;
}

void write_out_of_bounds(Channel& c, const char* function, std::uint32_t count, std::ptrdiff_t byte) {
  c.status = Status::WriteOutOfBounds;
  const std::string what = std::string(function) + " wrote past the " + std::to_string(count) +
                           " answers it was given (byte " + std::to_string(byte) + " after the last)";
  copy_message(c.message, sizeof c.message, what.c_str());
}

}  // namespace

QueryServer::QueryServer(ControlBlock& block, int control_fd, std::function<std::string()> install_query_filter)
    : block_(block), control_fd_(control_fd), install_query_filter_(std::move(install_query_filter)) {}

void QueryServer::start_threads() {
  for (std::size_t i = 0; i < kChannels; ++i) std::thread([this, i] { serve(i); }).detach();
}

std::uint32_t QueryServer::wait_for_request(Channel& c, std::uint32_t seen) {
  if (spin_yielding([&] { return c.request.load(std::memory_order_acquire) != seen; }, kWorkerSpin))
    return c.request.load(std::memory_order_acquire);
  // seq_cst store, then seq_cst load: paired with twinray's store of request and load of worker_sleeping
  // (isolated_plugin_backend.cpp), one side always sees the other.
  c.worker_sleeping.store(1, std::memory_order_seq_cst);
  std::uint32_t now;
  while ((now = c.request.load(std::memory_order_seq_cst)) == seen) futex_wait(&c.request, seen);
  c.worker_sleeping.store(0, std::memory_order_relaxed);
  return now;
}

void QueryServer::serve(std::size_t index) {
  set_thread_role(static_cast<std::int32_t>(index));
  install_alternate_signal_stack();
  Channel& c = block_.channels[index];
  // Requests are numbered from 1. Starting from 0 rather than from the word's current value matters: twinray
  // may post the first request before this thread has started.
  std::uint32_t seen = 0;
  for (;;) {
    seen = wait_for_request(c, seen);
    c.status = Status::Ok;
    c.message[0] = '\0';
    switch (c.op) {
      case Op::Build: run_build(c); break;
      case Op::Intersect: run_queries(c, true); break;
      case Op::Occluded: run_queries(c, false); break;
      case Op::IntersectBatch: run_batch(c, true); break;
      case Op::OccludedBatch: run_batch(c, false); break;
      case Op::Destroy: run_destroy(c);
      case Op::None: break;
    }
    c.response.store(seen, std::memory_order_seq_cst);
    if (c.parent_sleeping.load(std::memory_order_seq_cst) != 0) futex_wake_all(&c.response);
  }
}

void* QueryServer::instance_for(Channel& c) {
  const std::uint32_t index = c.instance;
  if (index >= kInstances) {
    c.status = Status::SetupFailed;
    copy_message(c.message, sizeof c.message, "the request names a plugin instance the worker cannot have");
    return nullptr;
  }
  if (selves_[index] == nullptr && c.op == Op::Build) {
    // A second instance, created on this query thread, in plugin code's usual guard. Instances are only
    // created by builds, which twinray never runs concurrently with anything else on the same worker.
    guarded(c, [&] { selves_[index] = plugin_->table().create(); });
    if (c.status == Status::Ok && selves_[index] == nullptr) {
      c.status = Status::BuildFailed;
      copy_message(c.message, sizeof c.message, "create() returned NULL for a second instance");
    }
  }
  if (selves_[index] == nullptr && c.status == Status::Ok) {
    c.status = Status::SetupFailed;
    copy_message(c.message, sizeof c.message, "the request names a plugin instance that was never built");
  }
  return c.status == Status::Ok ? selves_[index] : nullptr;
}

void QueryServer::run_queries(Channel& c, bool closest) {
  const std::uint32_t n = std::min<std::uint32_t>(c.count, static_cast<std::uint32_t>(kChunkRays));
  const twinray_plugin_v1& table = plugin_->table();
  const void* self = instance_for(c);
  if (self == nullptr) return;
  twinray_query_stats stats{};
  guarded(c, [&] {
    for (std::uint32_t k = 0; k < n; ++k) {
      c.current.store(k, std::memory_order_relaxed);
      const twinray_ray ray = c.rays[k];  // the plugin's copy: twinray does not touch it during the call
      errno = 0;                          // see crash_recorder.cpp: ENOMEM at a crash means a failed allocation
      if (closest) {
        twinray_hit hit = miss();
        const int found = table.intersect1(self, &ray, &hit, &stats);
        c.results[k].hit = hit;
        c.results[k].found = found != 0 ? 1 : 0;
      } else {
        c.results[k].found = table.occluded1(self, &ray, &stats) != 0 ? 1 : 0;
      }
    }
  });
  c.nodes_visited = stats.nodes_visited;
  c.primitives_tested = stats.primitives_tested;
}

void QueryServer::run_batch(Channel& c, bool closest) {
  const std::uint32_t n = std::min<std::uint32_t>(c.count, static_cast<std::uint32_t>(kChunkRays));
  const twinray_plugin_v1& table = plugin_->table();
  const void* self = instance_for(c);
  if (self == nullptr) return;
  if (closest ? table.intersect_batch == nullptr : table.occluded_batch == nullptr) {
    c.status = Status::SetupFailed;
    copy_message(c.message, sizeof c.message, "a batch request for a plugin without that batch function");
    return;
  }
  // The plugin's own copies of the rays and room for its answers: twinray does not touch the channel during
  // the call, but the plugin gets private buffers as the in-process backend gives it (a stack array there).
  twinray_ray rays[kBatchCallRays];
  twinray_hit hits[kBatchCallRays + kGuardHits];
  unsigned char occluded[kBatchCallRays + kGuardFlags];
  twinray_query_stats stats{};
  guarded(c, [&] {
    for (std::uint32_t begin = 0; begin < n; begin += static_cast<std::uint32_t>(kBatchCallRays)) {
      const std::uint32_t count = std::min<std::uint32_t>(n - begin, static_cast<std::uint32_t>(kBatchCallRays));
      c.current.store(begin, std::memory_order_relaxed);  // a crash or hang in this call is pinned to its first ray
      std::memcpy(rays, c.rays + begin, count * sizeof(twinray_ray));
      errno = 0;  // see crash_recorder.cpp
      if (closest) {
        for (std::uint32_t k = 0; k < count; ++k) hits[k] = miss();
        std::memset(hits + count, kGuardByte, kGuardHits * sizeof(twinray_hit));
        table.intersect_batch(self, rays, hits, count, &stats);
        if (const std::ptrdiff_t at = first_overwritten(hits + count, kGuardHits * sizeof(twinray_hit)); at >= 0) {
          write_out_of_bounds(c, "intersect_batch", count, at);
          return;
        }
        for (std::uint32_t k = 0; k < count; ++k) {
          c.results[begin + k].hit = hits[k];
          c.results[begin + k].found = hits[k].geom_id != TWINRAY_INVALID_ID ? 1 : 0;
        }
      } else {
        std::memset(occluded, 0, count);
        std::memset(occluded + count, kGuardByte, kGuardFlags);
        table.occluded_batch(self, rays, occluded, count, &stats);
        if (const std::ptrdiff_t at = first_overwritten(occluded + count, kGuardFlags); at >= 0) {
          write_out_of_bounds(c, "occluded_batch", count, at);
          return;
        }
        for (std::uint32_t k = 0; k < count; ++k) c.results[begin + k].found = occluded[k] != 0 ? 1 : 0;
      }
    }
    // Answered: the request ends on its last ray, as a single-call request does (twinray checks it).
    if (n > 0) c.current.store(n - 1, std::memory_order_relaxed);
  });
  c.nodes_visited = stats.nodes_visited;
  c.primitives_tested = stats.primitives_tested;
}

void QueryServer::run_build(Channel& c) {
  void* self = instance_for(c);
  if (self == nullptr) return;
  std::vector<twinray_mesh>& meshes = meshes_[c.instance];
  // The scene, mapped read-only and never unmapped: the plugin may keep pointers into it until destroy.
  const std::size_t bytes = c.geometry_bytes;
  void* mapping = bytes > 0 ? mmap(nullptr, bytes, PROT_READ, MAP_SHARED, control_fd_, static_cast<off_t>(c.geometry_offset))
                            : MAP_FAILED;
  if (mapping == MAP_FAILED) {
    c.status = Status::SetupFailed;
    copy_message(c.message, sizeof c.message, "cannot map the scene");
    return;
  }
  const auto* base = static_cast<const unsigned char*>(mapping);
  GeometryBlobHeader header;
  std::memcpy(&header, base, sizeof header);
  const std::size_t tables = sizeof header + header.mesh_count * sizeof(MeshRecord) + header.sphere_count * sizeof(twinray_sphere);
  const bool counts_fit = header.mesh_count < bytes && header.sphere_count < bytes && tables <= bytes;
  meshes.clear();
  bool fits = counts_fit;
  for (std::uint64_t m = 0; fits && m < header.mesh_count; ++m) {
    MeshRecord r;
    std::memcpy(&r, base + sizeof header + m * sizeof(MeshRecord), sizeof r);
    fits = r.positions_offset <= bytes && r.vertex_count <= (bytes - r.positions_offset) / (3 * sizeof(float)) &&
           r.indices_offset <= bytes && r.triangle_count <= (bytes - r.indices_offset) / (3 * sizeof(twinray_id));
    twinray_mesh mesh;
    mesh.geom_id = r.geom_id;
    mesh.positions = reinterpret_cast<const float*>(base + r.positions_offset);
    mesh.vertex_count = r.vertex_count;
    mesh.indices = reinterpret_cast<const twinray_id*>(base + r.indices_offset);
    mesh.triangle_count = r.triangle_count;
    meshes.push_back(mesh);
  }
  if (!fits) {
    c.status = Status::SetupFailed;
    copy_message(c.message, sizeof c.message, "the scene in shared memory is malformed");
    return;
  }
  twinray_geometry geometry;
  geometry.meshes = meshes.data();
  geometry.mesh_count = meshes.size();
  geometry.spheres = reinterpret_cast<const twinray_sphere*>(base + sizeof header + header.mesh_count * sizeof(MeshRecord));
  geometry.sphere_count = header.sphere_count;
  geometry.geom_id_end = header.geom_id_end;

  const twinray_plugin_v1& table = plugin_->table();
  char error[sizeof c.message] = {};
  int result = TWINRAY_ERROR;
  twinray_build_stats stats{};
  guarded(c, [&] {
    errno = 0;
    result = table.build(self, &geometry, error, sizeof error);
    if (result == TWINRAY_OK && table.build_stats != nullptr) table.build_stats(self, &stats);
  });
  if (c.status == Status::Ok) {
    if (result != TWINRAY_OK) {
      c.status = Status::BuildFailed;
      error[sizeof error - 1] = '\0';  // do not trust the plugin to terminate it
      copy_message(c.message, sizeof c.message, error);
    } else {
      c.build_stats.reported = table.build_stats != nullptr ? 1 : 0;
      c.build_stats.memory_bytes = stats.memory_bytes;
      c.build_stats.nodes = stats.nodes;
      c.build_stats.leaves = stats.leaves;
      c.build_stats.max_depth = stats.max_depth;
      c.build_stats.sah_cost = stats.sah_cost;
    }
  }
  // From here on the plugin cannot open any file: whatever it needed to read, it has read while building.
  // (Once: a second instance is built under the filter the first build installed.)
  if (query_filter_installed_) return;
  query_filter_installed_ = true;
  const std::string filter_error = install_query_filter_();
  if (!filter_error.empty()) {
    c.status = Status::SetupFailed;
    copy_message(c.message, sizeof c.message, filter_error.c_str());
  }
}

void QueryServer::run_destroy(Channel& c) {
  try {
    c.in_plugin.store(1, std::memory_order_relaxed);
    // The second instance first, then the first (its PluginLibrary's): the reverse of creation.
    if (selves_[1] != nullptr) plugin_->table().destroy(selves_[1]);
    plugin_->table().destroy(plugin_->self());
  } catch (...) {
    std::abort();  // reported as an abort in stage "destroy"
  }
  // exit, not _exit: the plugin's atexit handlers and static destructors run, as at the end of any program that
  // uses it, so one that crashes or hangs there is seen (twinray bounds the whole teardown by one call's limit
  // and reads the exit status). Threads the plugin left running end with the process. The crash recorder's
  // own atexit hook stands down; the query threads sleep on their channels and touch nothing exit() frees.
  std::fflush(nullptr);
  expect_clean_exit();
  std::exit(0);
}

}  // namespace twinray::plugin_worker
