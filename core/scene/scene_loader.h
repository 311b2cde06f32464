#pragma once
// Loading scenes. Every failure throws InputError naming the file and the place in it.

#include "core/scene/scene.h"

#include <filesystem>

namespace twinray {

// Loads a JSON scene (.json), a Mitsuba 3 scene (.xml, core/scene/mitsuba_scene.h) or wraps a bare mesh (.obj, .ply) in a default scene whose camera frames the
// mesh's bounding box. Relative paths inside a scene resolve against the scene file's folder.
Scene load_scene(const std::filesystem::path& path);

}  // namespace twinray
