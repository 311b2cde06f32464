#pragma once
// Reading a mesh file by its extension (.obj or .ply, any case).

#include "core/geometry/scene_geometry.h"
#include "core/scene/scene.h"

#include <filesystem>

namespace twinray {

bool is_mesh_file_extension(const std::filesystem::path& path);

// The raw mesh (not yet cleaned, geom_id 0). Throws InputError for a missing, unreadable, malformed or
// unsupported file.
TriangleMesh read_mesh_file(const std::filesystem::path& path, LoadReport& report);

}  // namespace twinray
