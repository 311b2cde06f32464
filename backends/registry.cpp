#include "backends/registry.h"

#include "backends/brute/brute_backend.h"
#include "backends/bvh/bvh_backend.h"
#include "backends/embree/embree_backend.h"
#include "backends/exact/exact_backend.h"
#include "backends/plugin/isolated_plugin_backend.h"
#include "backends/plugin/plugin_backend.h"
#include "backends/wide/wide_backend.h"

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <stdexcept>

namespace twinray {

namespace {
// A plugin in its own sandboxed worker process (the default: a plugin is code under test).
constexpr std::string_view kPluginPrefix = "plugin:";
// The same plugin loaded into this process: for plugins you trust, and for debugging one under gdb or a
// sanitizer. The name says what it does, not what it promises, so nobody picks it by accident for grading.
constexpr std::string_view kInProcessPluginPrefix = "plugin-inprocess:";

bool is_plugin_name(std::string_view name) {
  return name.starts_with(kPluginPrefix) || name.starts_with(kInProcessPluginPrefix);
}
}  // namespace

std::vector<std::string> backend_names() { return {"bvh8", "bvh", "embree", "embree-fast", "brute", "exact"}; }

std::unique_ptr<Backend> make_backend(std::string_view name) {
  if (name == "bvh8") return make_wide_backend();
  if (name == "bvh") return make_bvh_backend();
  if (name == "embree") return make_embree_backend(/*robust=*/true);
  if (name == "embree-fast") return make_embree_backend(/*robust=*/false);
  if (name == "brute") return make_brute_backend();
  if (name == "exact") return make_exact_backend();
  if (name.starts_with(kPluginPrefix))
    return make_isolated_plugin_backend(std::string(name.substr(kPluginPrefix.size())));
  if (name.starts_with(kInProcessPluginPrefix))
    return load_plugin_backend(std::string(name.substr(kInProcessPluginPrefix.size())));
  throw std::invalid_argument(fmt::format("unknown backend '{}' (choose from {}, or plugin:PATH, plugin-inprocess:PATH)",
                                          name, fmt::join(backend_names(), ", ")));
}

std::vector<std::string> parse_backend_list(std::string_view list) {
  std::vector<std::string> names;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t comma = list.find(',', start);
    const std::string_view item = list.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    if (item.empty()) throw std::invalid_argument(fmt::format("empty backend name in '{}'", list));
    const std::vector<std::string> builtin = backend_names();
    const bool known = is_plugin_name(item) || std::find(builtin.begin(), builtin.end(), item) != builtin.end();
    if (!known)
      throw std::invalid_argument(fmt::format("unknown backend '{}' (choose from {}, or plugin:PATH, plugin-inprocess:PATH)",
                                              item, fmt::join(backend_names(), ", ")));
    for (const std::string& n : names)
      if (n == item) throw std::invalid_argument(fmt::format("backend '{}' listed twice", item));
    names.emplace_back(item);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return names;
}

}  // namespace twinray
