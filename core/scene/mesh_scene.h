#pragma once
// A bare mesh file (.obj, .ply) wrapped in a default scene, so `twinray render bunny.obj` just works:
// one white diffuse shape (albedo 0.8) under a uniform white sky (radiance 1), seen by a 640x480 camera
// with a 40 degree vertical field of view that frames the mesh's bounding sphere from the +Z side,
// slightly above and to the right; 16 spp, unlimited depth.

#include "core/scene/scene.h"

#include <filesystem>

namespace twinray {

Scene load_bare_mesh_scene(const std::filesystem::path& mesh_file);

// The default camera for geometry with these bounds. Works for flat and empty bounds too.
CameraDesc framing_camera(const Bounds3& bounds, int width, int height, float vfov_deg);

}  // namespace twinray
