// libFuzzer target: the Mitsuba 3 XML scene reader (core/scene/mitsuba_scene.h).
//
// As for the JSON target, the scene is parsed as if it lived in a private folder holding two small valid
// meshes (tri.obj, tri.ply), so inputs that reference them reach the mesh loading, transform and material
// code. Contract under test: any byte string either gives a Scene or throws InputError.

#include "core/scene/mitsuba_scene.h"
#include "core/util/input_error.h"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

namespace {

std::filesystem::path make_scene_folder() {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("twinray-fuzz-xml-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "tri.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::ofstream(dir / "tri.ply") << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                    "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  return dir / "scene.xml";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path scene_file = make_scene_folder();
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const twinray::Scene scene = twinray::parse_mitsuba_scene(text, scene_file);
    (void)scene;
  } catch (const twinray::InputError&) {
  }
  return 0;
}
