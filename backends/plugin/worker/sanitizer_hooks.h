#pragma once
// In a sanitizer build (scripts/sanitize.sh), `new` beyond the memory limit does not throw std::bad_alloc:
// AddressSanitizer reports "out of memory" and ends the process itself. This hook notes such a report in the
// crash record, so the worker's end is still reported as cause "out-of-memory". Nothing in other builds.

#include "backends/plugin/worker_protocol.h"

namespace twinray::plugin_worker {

void install_sanitizer_hooks(CrashRecord& record);

}  // namespace twinray::plugin_worker
