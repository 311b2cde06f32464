#include "backends/plugin/worker/sanitizer_hooks.h"

#include "backends/plugin/sanitizer_build.h"

#include <cstring>

// AddressSanitizer's interface (<sanitizer/asan_interface.h>), declared weak so that builds without the
// sanitizer runtime link too; there the pointer is null and nothing is installed.
extern "C" void __asan_set_error_report_callback(void (*callback)(const char*)) __attribute__((weak));

namespace twinray::plugin_worker {

namespace {

CrashRecord* g_record = nullptr;

// Called by ASan with the text of its report, just before it ends the process.
void on_sanitizer_report(const char* report) {
  const bool memory = std::strstr(report, "out of memory") != nullptr ||
                      std::strstr(report, "allocation-size-too-big") != nullptr ||
                      std::strstr(report, "rss-limit-exceeded") != nullptr;
  if (memory && g_record != nullptr) g_record->allocation_failed.store(1);
}

}  // namespace

void install_sanitizer_hooks(CrashRecord& record) {
  if constexpr (!kAddressSanitizer) return;
  g_record = &record;
  if (__asan_set_error_report_callback != nullptr) __asan_set_error_report_callback(on_sanitizer_report);
}

}  // namespace twinray::plugin_worker
