#include "backends/plugin/plugin_library.h"

#include "core/util/input_error.h"

#include <dlfcn.h>

#include <string>
#include <utility>

namespace twinray {

namespace {

// Closes a dlopen handle on every early exit of load().
struct HandleGuard {
  void* handle;
  ~HandleGuard() {
    if (handle != nullptr) dlclose(handle);
  }
};

}  // namespace

std::unique_ptr<PluginLibrary> PluginLibrary::load(const std::filesystem::path& so) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(so, ec))
    throw InputError(so, "", "plugin library not found (expected a shared library, e.g. libmybvh.so)");
  // An absolute path: dlopen would otherwise search the library path for a bare file name.
  const std::filesystem::path absolute = std::filesystem::absolute(so);
  dlerror();  // clear any stale message
  HandleGuard guard{dlopen(absolute.c_str(), RTLD_NOW | RTLD_LOCAL)};
  if (guard.handle == nullptr) {
    const char* why = dlerror();
    throw InputError(so, "", std::string("cannot load it as a shared library: ") + (why != nullptr ? why : "unknown reason"));
  }

  dlerror();
  void* symbol = dlsym(guard.handle, TWINRAY_PLUGIN_ENTRY_SYMBOL);
  if (symbol == nullptr)
    throw InputError(so, "",
                     "does not export " TWINRAY_PLUGIN_ENTRY_SYMBOL " (define it with C linkage and default "
                     "visibility, see docs/plugin-abi.md)");
  // POSIX guarantees that a dlsym result can be converted to a function pointer.
  const auto entry = reinterpret_cast<twinray_plugin_entry_fn>(symbol);
  const twinray_plugin_v1* table = entry();
  if (table == nullptr) throw InputError(so, "", TWINRAY_PLUGIN_ENTRY_SYMBOL " returned NULL");
  if (table->abi_version != TWINRAY_PLUGIN_ABI_VERSION)
    throw InputError(so, "",
                     "plugin ABI version mismatch: the plugin was built for version " +
                         std::to_string(table->abi_version) + ", this twinray implements version " +
                         std::to_string(TWINRAY_PLUGIN_ABI_VERSION) + " (rebuild it against backends/plugin/twinray_plugin.h)");
  if (table->name == nullptr || table->name[0] == '\0') throw InputError(so, "", "the plugin table has no name");
  const std::pair<const char*, bool> required[] = {
      {"create", table->create != nullptr},         {"destroy", table->destroy != nullptr},
      {"build", table->build != nullptr},           {"intersect1", table->intersect1 != nullptr},
      {"occluded1", table->occluded1 != nullptr},
  };
  for (const auto& [function, present] : required)
    if (!present) throw InputError(so, "", std::string("the plugin table leaves the required function '") + function + "' NULL");

  std::unique_ptr<PluginLibrary> library(new PluginLibrary(so, guard.handle, *table));
  guard.handle = nullptr;  // owned by `library` from here on
  library->self_ = library->table_.create();
  if (library->self_ == nullptr) throw InputError(so, "", "the plugin's create() returned NULL");
  return library;
}

PluginLibrary::~PluginLibrary() {
  if (self_ != nullptr) table_.destroy(self_);
  if (handle_ != nullptr) dlclose(handle_);
}

}  // namespace twinray
