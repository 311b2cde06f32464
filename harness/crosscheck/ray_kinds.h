#pragma once
// The kinds of rays a cross-check shoots, each probing a different part of a backend:
//   camera   coherent primary rays over the image (one jittered ray per stratum of pixels)
//   uniform  incoherent rays through the scene bounds, origins inside and around the box
//   diffuse  cosine-distributed bounce rays leaving first hits (origins on surfaces: self-intersection)
//   shadow   finite segments from first hits to points on emitters (or random points): any-hit queries
//   axis     exactly zero direction components of both signs, along axes and in coordinate planes, through
//            vertices and from the faces of the scene's box (axis_rays.h): a slab test's 0 * inf and -0

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace twinray::crosscheck {

enum class RayKind { Camera, Uniform, Diffuse, Shadow, Axis };

inline constexpr RayKind kAllRayKinds[] = {RayKind::Camera, RayKind::Uniform, RayKind::Diffuse, RayKind::Shadow,
                                           RayKind::Axis};

std::string_view to_string(RayKind kind);
std::optional<RayKind> parse_ray_kind(std::string_view name);
// "camera,shadow" -> kinds; throws std::invalid_argument naming the bad item.
std::vector<RayKind> parse_ray_kinds(std::string_view list);

}  // namespace twinray::crosscheck
