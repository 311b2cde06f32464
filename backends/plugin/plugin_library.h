#pragma once
// A plugin library loaded into the calling process: the dlopen handle, a copy of the plugin's function table
// and one instance of the plugin (create() already called).
//
// This is the one place that knows how to load and check a plugin. Two callers use it:
//  - the worker process of the isolated backend (backends/plugin/worker), where plugin code is allowed to run;
//  - the in-process backend `plugin-inprocess:PATH` (plugin_backend.h), for trusted plugins and debugging.
// It depends on nothing but the C ABI header and InputError, so the worker executable stays small.

#include "backends/plugin/twinray_plugin.h"

#include <filesystem>
#include <memory>
#include <string>

namespace twinray {

class PluginLibrary {
 public:
  // Loads `so`, checks its entry point and table, and creates one instance. Throws twinray::InputError naming
  // `so` when the file is missing, is not a loadable shared library, does not export twinray_plugin_entry,
  // returns NULL from it, was built against another ABI version, has no name, leaves a required function
  // NULL, or when create() returns NULL.
  static std::unique_ptr<PluginLibrary> load(const std::filesystem::path& so);

  ~PluginLibrary();  // destroy(self), then dlclose
  PluginLibrary(const PluginLibrary&) = delete;
  PluginLibrary& operator=(const PluginLibrary&) = delete;

  // A copy: the plugin's own table need not stay writable or aligned.
  const twinray_plugin_v1& table() const { return table_; }
  void* self() const { return self_; }
  const std::filesystem::path& path() const { return path_; }
  // "plugin:" + the table's name, the name every twinray report uses.
  std::string backend_name() const { return std::string("plugin:") + table_.name; }

 private:
  PluginLibrary(std::filesystem::path path, void* handle, const twinray_plugin_v1& table)
      : path_(std::move(path)), handle_(handle), table_(table) {}

  std::filesystem::path path_;
  void* handle_ = nullptr;
  twinray_plugin_v1 table_;
  void* self_ = nullptr;
};

}  // namespace twinray
