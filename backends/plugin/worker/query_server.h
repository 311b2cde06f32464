#pragma once
// The worker's side of the channels (worker_protocol.h): one thread per channel waits for a request, calls
// the plugin and answers. Single-ray requests go through intersect1 / occluded1, with the ray's index in
// shared memory before each call, so a crash or a hang is attributed to exactly one ray; batch requests go
// through intersect_batch / occluded_batch in calls of kBatchCallRays rays, attributed to the call's first ray.
// After every call the worker checks what the plugin must leave alone: the floating-point control bits
// (fp_environment.h) and, for batch calls, guard bytes after the answers.

#include "backends/plugin/plugin_library.h"
#include "backends/plugin/worker_protocol.h"

#include <functional>
#include <string>
#include <vector>

namespace twinray::plugin_worker {

class QueryServer {
 public:
  // `install_query_filter` runs after build, before the answer goes back (seccomp_filter.h, phase Querying);
  // it returns an error text or an empty string.
  QueryServer(ControlBlock& block, int control_fd, std::function<std::string()> install_query_filter);

  // Starts the channel threads. They answer requests only once the parent has seen Startup::Ready, which is
  // after set_plugin.
  void start_threads();
  void set_plugin(PluginLibrary& plugin) {
    plugin_ = &plugin;
    selves_[0] = plugin.self();
  }

 private:
  [[noreturn]] void serve(std::size_t index);
  std::uint32_t wait_for_request(Channel& c, std::uint32_t seen);
  void run_build(Channel& c);
  // The instance a request is for, or nullptr (the status says why) when it names none there is: instance 1
  // is created (table.create) by the first Build addressed to it.
  void* instance_for(Channel& c);
  void run_queries(Channel& c, bool closest);
  // The plugin's intersect_batch / occluded_batch over the request, in calls of kBatchCallRays rays.
  void run_batch(Channel& c, bool closest);
  [[noreturn]] void run_destroy(Channel& c);

  ControlBlock& block_;
  int control_fd_;
  std::function<std::string()> install_query_filter_;
  PluginLibrary* plugin_ = nullptr;
  // The instances (worker_protocol.h, kInstances); [0] is the PluginLibrary's own.
  void* selves_[kInstances] = {};
  // The scene as each instance sees it; valid until destroy (the ABI's promise).
  std::vector<twinray_mesh> meshes_[kInstances];
  bool query_filter_installed_ = false;
};

}  // namespace twinray::plugin_worker
