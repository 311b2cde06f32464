#include "backends/registry.h"

#include "backends/brute/brute_backend.h"
#include "backends/bvh/bvh_backend.h"
#include "backends/embree/embree_backend.h"
#include "backends/exact/exact_backend.h"
#include "backends/plugin/plugin_backend.h"

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <stdexcept>

namespace twinray {

namespace {
constexpr std::string_view kPluginPrefix = "plugin:";
}

std::vector<std::string> backend_names() { return {"bvh", "embree", "embree-fast", "brute", "exact"}; }

std::unique_ptr<Backend> make_backend(std::string_view name) {
  if (name == "bvh") return make_bvh_backend();
  if (name == "embree") return make_embree_backend(/*robust=*/true);
  if (name == "embree-fast") return make_embree_backend(/*robust=*/false);
  if (name == "brute") return make_brute_backend();
  if (name == "exact") return make_exact_backend();
  if (name.starts_with(kPluginPrefix)) return load_plugin_backend(std::string(name.substr(kPluginPrefix.size())));
  throw std::invalid_argument(
      fmt::format("unknown backend '{}' (choose from {}, or plugin:PATH)", name, fmt::join(backend_names(), ", ")));
}

std::vector<std::string> parse_backend_list(std::string_view list) {
  std::vector<std::string> names;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t comma = list.find(',', start);
    const std::string_view item = list.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    if (item.empty()) throw std::invalid_argument(fmt::format("empty backend name in '{}'", list));
    const std::vector<std::string> builtin = backend_names();
    const bool known = item.starts_with(kPluginPrefix) || std::find(builtin.begin(), builtin.end(), item) != builtin.end();
    if (!known)
      throw std::invalid_argument(
          fmt::format("unknown backend '{}' (choose from {}, or plugin:PATH)", item, fmt::join(backend_names(), ", ")));
    for (const std::string& n : names)
      if (n == item) throw std::invalid_argument(fmt::format("backend '{}' listed twice", item));
    names.emplace_back(item);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return names;
}

}  // namespace twinray
