#pragma once
// The worker's file-system sandbox (Landlock, Linux 5.13 and later): from here on, the calling thread and the
// threads it creates may read (and map as code) only what loading a plugin needs, and write nothing.
//
//   readable   the plugin's folder; the system library folders (/lib, /lib64, /usr/lib, /usr/lib64,
//              /usr/local/lib, and the folders of LD_LIBRARY_PATH); /etc/ld.so.cache; /sys/devices/system/cpu
//              (how many CPUs: glibc, OpenMP and TBB ask)
//   writable   nothing (already open descriptors, i.e. the output pipe and the shared memory, stay usable)
// With Landlock ABI 4 or later TCP bind/connect are denied too, and with ABI 6 or later signals to processes
// outside the sandbox and abstract UNIX sockets. Landlock restricts only the calling thread and its future
// threads (this kernel interface has no way to reach existing threads), so the worker applies it on its main
// thread before it creates any other.

#include <filesystem>
#include <string>

namespace twinray::plugin_worker {

struct LandlockOutcome {
  bool applied = false;
  int abi = 0;              // the kernel's Landlock ABI version (0: none)
  std::string description;  // what is in force, or why nothing is
};

LandlockOutcome restrict_file_system(const std::filesystem::path& plugin);

}  // namespace twinray::plugin_worker
