#include "core/scene/scene_loader.h"

#include "core/scene/input_file.h"
#include "core/scene/json_scene.h"
#include "core/scene/mesh_file.h"
#include "core/scene/mesh_scene.h"
#include "core/scene/mitsuba_scene.h"
#include "core/util/input_error.h"

#include <string>

namespace twinray {

Scene load_scene(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".json") return load_json_scene(path);
  if (ext == ".xml") return load_mitsuba_scene(path);
  if (is_mesh_file_extension(path)) return load_bare_mesh_scene(path);
  require_regular_file(path);  // "file not found" beats "unknown type" when both apply
  throw InputError(path, "", "unknown scene file type '" + ext + "' (expected .json, .xml, .obj or .ply)");
}

}  // namespace twinray
