// A plugin that hangs in its first query while forging its worker's progress, for
// tests/test_plugin_isolation.cpp: the worker publishes the index of the ray in flight (worker_protocol.h,
// Channel::current) and twinray restarts a ray's time limit whenever that index moves. This plugin knows the
// protocol, maps the worker's shared memory (descriptor 3) in build, and in its first query never returns
// while it moves the index of every channel that is running plugin code forward, 1, 2, 3, ... every 50 ms:
// to twinray, rays that take 50 ms each. No worker moves it past the request's last ray.

#include "backends/plugin/twinray_plugin.h"
#include "backends/plugin/worker_protocol.h"

#include <sys/mman.h>
#include <sys/stat.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <new>
#include <thread>

namespace {

namespace pw = twinray::plugin_worker;

pw::ControlBlock* g_block = nullptr;

void* forging_create() { return new (std::nothrow) int(0); }
void forging_destroy(void* self) { delete static_cast<int*>(self); }

int forging_build(void*, const twinray_geometry*, char*, std::size_t) {
  struct stat st {};
  if (fstat(pw::kControlFd, &st) != 0) return TWINRAY_ERROR;
  void* m = mmap(nullptr, sizeof(pw::ControlBlock), PROT_READ | PROT_WRITE, MAP_SHARED, pw::kControlFd, 0);
  if (m == MAP_FAILED) return TWINRAY_ERROR;
  g_block = static_cast<pw::ControlBlock*>(m);
  return TWINRAY_OK;
}

[[noreturn]] void hang_forging_progress() {
  for (std::uint32_t beat = 1;; ++beat) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    for (pw::Channel& c : g_block->channels)
      if (c.in_plugin.load() != 0) c.current.store(beat);
  }
}

int forging_intersect1(const void*, const twinray_ray*, twinray_hit*, twinray_query_stats*) { hang_forging_progress(); }
int forging_occluded1(const void*, const twinray_ray*, twinray_query_stats*) { hang_forging_progress(); }

const twinray_plugin_v1 forging_table = {
    TWINRAY_PLUGIN_ABI_VERSION, "forging", 0u, forging_create, forging_destroy, forging_build,
    forging_intersect1,         forging_occluded1, nullptr, nullptr, nullptr,
};

}  // namespace

TWINRAY_PLUGIN_EXPORT const twinray_plugin_v1* twinray_plugin_entry(void) { return &forging_table; }
