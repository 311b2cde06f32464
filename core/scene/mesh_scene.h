#pragma once
// A bare mesh file (.obj, .ply) wrapped in a default scene, so `twinray render bunny.obj` shows its shape
// the way a mesh viewer would (docs/scene-format.md, "Bare meshes"):
//  - the mesh, mid-grey diffuse (albedo 0.5);
//  - a ground plane under its bounding box (a square, darker grey, half as wide as 2.5 bounding radii
//    around the mesh, a hair below its lowest point so no face of the mesh lies in it): contact shadows
//    and a floor to stand on;
//  - a sky with a sun, as a procedural latitude-longitude map (kSkyWidth x kSkyHeight, in memory): a blue
//    gradient from the horizon up, and a sun disk of kSunRadiusDeg degrees from the upper left, in front,
//    which casts soft shadows; seen by a 640x480 camera with a 40 degree vertical field of view that frames
//    the mesh's bounding sphere from the +Z side, slightly above and to the right (+Y is up);
//  - 16 spp, unlimited depth.
// The plane is ordinary geometry (geometry id 1), so renders, crosscheck and the benchmarks all see the
// same scene; Scene::additions lists what was added.

#include "core/scene/scene.h"

#include <filesystem>

namespace twinray {

Scene load_bare_mesh_scene(const std::filesystem::path& mesh_file);

inline constexpr int kSkyWidth = 512, kSkyHeight = 256;
inline constexpr double kSunRadiusDeg = 2.5;
// Irradiance from the sun on a surface facing it, and its direction (toward the sun, unnormalised).
inline constexpr double kSunIrradiance = 2.2;
inline constexpr double kSunDirection[3] = {-0.45, 0.75, 0.5};

// The sky with a sun (RGB radiance, top row = zenith, twinray's lat-long convention).
Image sky_with_sun();

// The default camera for geometry with these bounds. Works for flat and empty bounds too.
CameraDesc framing_camera(const Bounds3& bounds, int width, int height, float vfov_deg);

}  // namespace twinray
