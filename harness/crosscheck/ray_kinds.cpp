#include "harness/crosscheck/ray_kinds.h"

#include <fmt/core.h>

#include <stdexcept>

namespace twinray::crosscheck {

std::string_view to_string(RayKind kind) {
  switch (kind) {
    case RayKind::Camera: return "camera";
    case RayKind::Uniform: return "uniform";
    case RayKind::Diffuse: return "diffuse";
    case RayKind::Shadow: return "shadow";
    case RayKind::Axis: return "axis";
  }
  return "?";
}

std::optional<RayKind> parse_ray_kind(std::string_view name) {
  for (RayKind k : kAllRayKinds)
    if (to_string(k) == name) return k;
  return std::nullopt;
}

std::vector<RayKind> parse_ray_kinds(std::string_view list) {
  std::vector<RayKind> kinds;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = list.find(',', start);
    const std::string_view item = list.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    const std::optional<RayKind> kind = parse_ray_kind(item);
    if (!kind) throw std::invalid_argument(fmt::format("unknown ray kind '{}' (choose from camera, uniform, diffuse, shadow, axis)", item));
    for (RayKind k : kinds)
      if (k == *kind) throw std::invalid_argument(fmt::format("ray kind '{}' listed twice", item));
    kinds.push_back(*kind);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return kinds;
}

}  // namespace twinray::crosscheck
