#include "backends/plugin/worker/landlock_rules.h"

#include <fcntl.h>
#include <linux/landlock.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <vector>

// Access rights and attribute fields newer than the kernel headers of Debian 12 (Linux 6.1 UAPI); the values
// are the kernel's ABI and never change.
#ifndef LANDLOCK_ACCESS_FS_TRUNCATE
#define LANDLOCK_ACCESS_FS_TRUNCATE (1ULL << 14)
#endif
#ifndef LANDLOCK_ACCESS_FS_IOCTL_DEV
#define LANDLOCK_ACCESS_FS_IOCTL_DEV (1ULL << 15)
#endif
#ifndef LANDLOCK_ACCESS_NET_BIND_TCP
#define LANDLOCK_ACCESS_NET_BIND_TCP (1ULL << 0)
#define LANDLOCK_ACCESS_NET_CONNECT_TCP (1ULL << 1)
#endif
#ifndef LANDLOCK_SCOPE_ABSTRACT_UNIX_SOCKET
#define LANDLOCK_SCOPE_ABSTRACT_UNIX_SOCKET (1ULL << 0)
#define LANDLOCK_SCOPE_SIGNAL (1ULL << 1)
#endif

namespace twinray::plugin_worker {

namespace {

// struct landlock_ruleset_attr as of ABI 6; older kernels get a prefix of it (the size says how much).
struct RulesetAttr {
  std::uint64_t handled_access_fs;
  std::uint64_t handled_access_net;
  std::uint64_t scoped;
};

// The file-system rights each ABI version knows: asking an older kernel to handle a newer right fails.
std::uint64_t handled_fs_rights(int abi) {
  std::uint64_t rights = (1ULL << 13) - 1;  // ABI 1: EXECUTE .. MAKE_SYM
  if (abi >= 2) rights |= LANDLOCK_ACCESS_FS_REFER;
  if (abi >= 3) rights |= LANDLOCK_ACCESS_FS_TRUNCATE;
  if (abi >= 5) rights |= LANDLOCK_ACCESS_FS_IOCTL_DEV;
  return rights;
}

std::string errno_text() { return std::strerror(errno); }

// Folders (and files) the dynamic loader reads from.
std::vector<std::filesystem::path> readable_paths(const std::filesystem::path& plugin) {
  std::vector<std::filesystem::path> paths = {plugin.parent_path(), "/lib",  "/lib64", "/usr/lib",
                                              "/usr/lib64",          "/usr/local/lib", "/etc/ld.so.cache",
                                              "/sys/devices/system/cpu"};
  if (const char* list = std::getenv("LD_LIBRARY_PATH")) {
    std::string_view rest(list);
    while (!rest.empty()) {
      const std::size_t colon = rest.find(':');
      const std::string_view item = rest.substr(0, colon);
      if (!item.empty()) paths.emplace_back(std::string(item));
      if (colon == std::string_view::npos) break;
      rest.remove_prefix(colon + 1);
    }
  }
  return paths;
}

}  // namespace

LandlockOutcome restrict_file_system(const std::filesystem::path& plugin) {
  LandlockOutcome outcome;
  const long abi = syscall(SYS_landlock_create_ruleset, nullptr, 0, LANDLOCK_CREATE_RULESET_VERSION);
  if (abi < 1) {
    outcome.description = "Landlock unavailable (" + errno_text() + "): the plugin may read any file the user can";
    return outcome;
  }
  outcome.abi = static_cast<int>(abi);

  RulesetAttr attr{};
  attr.handled_access_fs = handled_fs_rights(outcome.abi);
  std::size_t attr_size = sizeof(std::uint64_t);
  if (abi >= 4) {
    attr.handled_access_net = LANDLOCK_ACCESS_NET_BIND_TCP | LANDLOCK_ACCESS_NET_CONNECT_TCP;
    attr_size = 2 * sizeof(std::uint64_t);
  }
  if (abi >= 6) {
    attr.scoped = LANDLOCK_SCOPE_ABSTRACT_UNIX_SOCKET | LANDLOCK_SCOPE_SIGNAL;
    attr_size = sizeof(RulesetAttr);
  }
  const int ruleset = static_cast<int>(syscall(SYS_landlock_create_ruleset, &attr, attr_size, 0));
  if (ruleset < 0) {
    outcome.description = "Landlock ruleset refused (" + errno_text() + ")";
    return outcome;
  }

  const std::uint64_t read_dir = LANDLOCK_ACCESS_FS_EXECUTE | LANDLOCK_ACCESS_FS_READ_FILE | LANDLOCK_ACCESS_FS_READ_DIR;
  const std::uint64_t read_file = LANDLOCK_ACCESS_FS_EXECUTE | LANDLOCK_ACCESS_FS_READ_FILE;
  int folders = 0;
  for (const std::filesystem::path& p : readable_paths(plugin)) {
    const int fd = open(p.c_str(), O_PATH | O_CLOEXEC);
    if (fd < 0) continue;  // a folder this system does not have
    struct stat st {};
    fstat(fd, &st);
    landlock_path_beneath_attr rule{};
    rule.allowed_access = S_ISDIR(st.st_mode) ? read_dir : read_file;  // directory rights are refused on a file
    rule.parent_fd = fd;
    if (syscall(SYS_landlock_add_rule, ruleset, LANDLOCK_RULE_PATH_BENEATH, &rule, 0) == 0) ++folders;
    close(fd);
  }
  // Landlock (like seccomp) requires no_new_privs unless the caller has CAP_SYS_ADMIN; set either way.
  prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0);
  const long restricted = syscall(SYS_landlock_restrict_self, ruleset, 0);
  const std::string restrict_error = restricted != 0 ? errno_text() : std::string();
  close(ruleset);
  if (restricted != 0) {
    outcome.description = "Landlock restriction refused (" + restrict_error + ")";
    return outcome;
  }
  outcome.applied = true;
  outcome.description = "Landlock ABI " + std::to_string(abi) + ": files read-only under " + std::to_string(folders) +
                        " paths (the plugin's folder, system libraries), nothing writable";
  if (abi >= 4) outcome.description += ", no TCP";
  if (abi >= 6) outcome.description += ", no signals or abstract sockets beyond the worker";
  return outcome;
}

}  // namespace twinray::plugin_worker
