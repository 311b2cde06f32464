#include "backends/plugin/worker/resource_limits.h"

#include "backends/plugin/sanitizer_build.h"

#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace twinray::plugin_worker {

namespace {

constexpr rlim_t kOpenFiles = 64;

void set_limit(int resource, rlim_t value, const char* name) {
  const rlimit limit{value, value};
  if (setrlimit(resource, &limit) != 0)
    throw std::runtime_error(std::string("setrlimit(") + name + "): " + std::strerror(errno));
}

// Address space in use now (the first field of /proc/self/statm, in pages).
std::uint64_t address_space_in_use() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0;
  unsigned long long pages = 0;
  if (std::fscanf(f, "%llu", &pages) != 1) pages = 0;
  std::fclose(f);
  return pages * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE));
}

}  // namespace

std::string apply_resource_limits(std::uint64_t memory_bytes) {
  set_limit(RLIMIT_CORE, 0, "RLIMIT_CORE");
  set_limit(RLIMIT_NOFILE, kOpenFiles, "RLIMIT_NOFILE");
  const std::uint64_t base = kAddressSanitizer ? address_space_in_use() : 0;
  set_limit(RLIMIT_AS, static_cast<rlim_t>(base + memory_bytes), "RLIMIT_AS");
  std::string s = "RLIMIT_AS " + std::to_string(memory_bytes >> 20) + " MiB";
  if (kAddressSanitizer) s += " beyond AddressSanitizer's " + std::to_string(base >> 30) + " GiB of reservations";
  return s + ", RLIMIT_NOFILE " + std::to_string(kOpenFiles) + ", RLIMIT_CORE 0";
}

}  // namespace twinray::plugin_worker
