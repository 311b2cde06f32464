#pragma once
// The JSON scene format (documented in docs/scene-format.md).
//
// Everything is validated: types, ranges, unknown keys (so a typo is an error, not a silently ignored
// setting) and material references. Errors are InputError with "line L:C" for JSON syntax errors and a
// JSON pointer ("/shapes/3/radius") for everything else; errors inside a referenced mesh file name that file.

#include "core/scene/scene.h"

#include <filesystem>
#include <string_view>

namespace twinray {

Scene load_json_scene(const std::filesystem::path& scene_file);

// The same from text in memory: `scene_file` names the scene in errors, and its folder is where relative
// paths inside the scene resolve.
Scene parse_json_scene(std::string_view text, const std::filesystem::path& scene_file);

}  // namespace twinray
