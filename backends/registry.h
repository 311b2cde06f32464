#pragma once
// Backends by name: the one place that knows every implementation.
//
//   bvh8          the same SAH tree collapsed into 8-wide SIMD nodes, kernels chosen at run time (backends/wide)
//   bvh           hand-written binned SAH BVH, binary, 32-byte nodes: the textbook reference (backends/bvh)
//   embree        Embree 3, RTC_SCENE_FLAG_ROBUST: the correctness reference
//   embree-fast   Embree 3, default flags: the speed reference
//   brute         a loop over every primitive: the oracle
//   exact         exact arithmetic (GMP/MPFR): the true closest hit, correctly rounded; the arbiter's reference
//   plugin:PATH   an external BVH loaded from a shared library through the C ABI (backends/plugin), run in
//                 an isolated, sandboxed worker process: a crash or hang of the plugin is a PluginFailure
//   plugin-inprocess:PATH  the same, loaded into this process (trusted plugins, debugging)

#include "core/backend/backend.h"

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace twinray {

// Throws std::invalid_argument naming the valid choices for an unknown name, InputError for a bad plugin,
// PluginFailure (backends/plugin/plugin_failure.h) when a plugin crashes or hangs while loading.
std::unique_ptr<Backend> make_backend(std::string_view name);

// The built-in names, in the order help texts list them.
std::vector<std::string> backend_names();

// Splits "a,b,c" and checks every name (built-in, plugin:PATH or plugin-inprocess:PATH). Throws
// std::invalid_argument.
std::vector<std::string> parse_backend_list(std::string_view list);

}  // namespace twinray
