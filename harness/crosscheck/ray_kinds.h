#pragma once
// The kinds of rays a cross-check shoots, each probing a different part of a backend:
//   camera   coherent primary rays over the image (one jittered ray per stratum of pixels)
//   uniform  incoherent rays through the scene bounds, origins inside and around the box
//   diffuse  cosine-distributed bounce rays leaving first hits (origins on surfaces: self-intersection)
//   shadow   finite segments from first hits to points on emitters (or random points): any-hit queries

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace twinray::crosscheck {

enum class RayKind { Camera, Uniform, Diffuse, Shadow };

inline constexpr RayKind kAllRayKinds[] = {RayKind::Camera, RayKind::Uniform, RayKind::Diffuse, RayKind::Shadow};

std::string_view to_string(RayKind kind);
std::optional<RayKind> parse_ray_kind(std::string_view name);
// "camera,shadow" -> kinds; throws std::invalid_argument naming the bad item.
std::vector<RayKind> parse_ray_kinds(std::string_view list);

}  // namespace twinray::crosscheck
