#include "core/scene/mesh_file.h"

#include "core/scene/input_file.h"
#include "core/scene/obj_reader.h"
#include "core/scene/ply_reader.h"
#include "core/util/input_error.h"

#include <string>

namespace twinray {

bool is_mesh_file_extension(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  return ext == ".obj" || ext == ".ply";
}

TriangleMesh read_mesh_file(const std::filesystem::path& path, LoadReport& report) {
  const std::string ext = lower_extension(path);
  if (ext == ".obj") return read_obj(path, report);
  if (ext == ".ply") return read_ply(path, report);
  require_regular_file(path);  // "file not found" is the more useful message when both apply
  throw InputError(path, "", "unsupported mesh format '" + ext + "' (expected .obj or .ply)");
}

}  // namespace twinray
