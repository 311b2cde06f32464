#pragma once
// A backend loaded at run time from a shared library that implements the C ABI of twinray_plugin.h, running
// the plugin's code inside this process: `plugin-inprocess:PATH`, for plugins you trust and for debugging a
// plugin under gdb or a sanitizer. A plugin that crashes takes the calling process down with it; `plugin:PATH`
// runs the same plugin in an isolated, sandboxed worker process instead (isolated_plugin_backend.h).
//
// The adapter owns the library handle and the plugin instance, checks every ray before the plugin sees it
// (an invalid ray is a miss, core/geometry/ray.h), converts between twinray's types and the ABI's plain C
// structs, and turns plugin failures into C++ exceptions. See docs/plugin-abi.md.

#include "core/backend/backend.h"

#include <filesystem>
#include <memory>

namespace twinray {

// Loads `so` and checks its entry point. Throws twinray::InputError (naming the file) when the file is
// missing, is not a loadable shared library, does not export twinray_plugin_entry, was built against
// another ABI version, or leaves a required function pointer null.
std::unique_ptr<Backend> load_plugin_backend(const std::filesystem::path& so);

}  // namespace twinray
