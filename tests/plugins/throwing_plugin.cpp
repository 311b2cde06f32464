// A plugin in C++ for tests/test_plugin_isolation.cpp. Its build does what ordinary C++ plugins do (std::vector,
// new, std::thread, a mutex, iostream to stdout), which the worker's sandbox must allow. Its queries answer
// "miss", except on a ray whose direction has an exactly zero component, where it lets a C++ exception escape
// through the C ABI (which the ABI forbids): std::runtime_error, or with TWINRAY_THROWING_BAD_ALLOC the
// std::bad_alloc of allocating without bound.
#include "twinray_plugin.h"

#include <iostream>
#include <memory>
#include <mutex>
#include <new>
#include <numeric>
#include <stdexcept>
#include <thread>
#include <vector>

namespace {

struct Instance {
  std::vector<int> numbers;
  long long sum = 0;
};

void* create() { return new Instance; }

void destroy(void* self) { delete static_cast<Instance*>(self); }

int build(void* self, const twinray_geometry* geometry, char*, size_t) {
  auto* instance = static_cast<Instance*>(self);
  instance->numbers.resize(100000);
  std::iota(instance->numbers.begin(), instance->numbers.end(), 0);
  std::mutex mutex;
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      const auto partial = std::make_unique<long long>(0);
      for (std::size_t i = static_cast<std::size_t>(t); i < instance->numbers.size(); i += 4) *partial += instance->numbers[i];
      const std::lock_guard lock(mutex);
      instance->sum += *partial;
    });
  for (std::thread& t : threads) t.join();
  std::cout << "built " << geometry->mesh_count << " meshes with 4 threads, sum " << instance->sum << std::endl;
  return TWINRAY_OK;
}

bool has_zero_component(const twinray_ray* ray) { return ray->dir[0] == 0.0f || ray->dir[1] == 0.0f || ray->dir[2] == 0.0f; }

[[noreturn]] void misbehave() {
#ifdef TWINRAY_THROWING_BAD_ALLOC
  std::vector<std::unique_ptr<char[]>> blocks;
  for (;;) {
    blocks.emplace_back(new char[1 << 20]);
    std::fill_n(blocks.back().get(), 1 << 20, '\1');
  }
#else
  throw std::runtime_error("zero direction component");
#endif
}

int intersect1(const void*, const twinray_ray* ray, twinray_hit*, twinray_query_stats*) {
  if (has_zero_component(ray)) misbehave();
  return 0;
}

int occluded1(const void*, const twinray_ray* ray, twinray_query_stats*) {
  if (has_zero_component(ray)) misbehave();
  return 0;
}

const twinray_plugin_v1 table = {
    TWINRAY_PLUGIN_ABI_VERSION, "throwing", 0u, create, destroy, build, intersect1, occluded1, nullptr, nullptr, nullptr,
};

}  // namespace

TWINRAY_PLUGIN_EXPORT const twinray_plugin_v1* twinray_plugin_entry(void) { return &table; }
