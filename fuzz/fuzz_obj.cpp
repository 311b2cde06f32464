// libFuzzer target: the OBJ reader, followed by the geometry cleanup the loaders always run after it.
// Contract under test: any byte string either parses into a mesh satisfying the SceneGeometry invariants
// or throws InputError. Any other exception, a crash, a sanitizer report or a hang is a finding.

#include "core/scene/geometry_cleanup.h"
#include "core/scene/obj_reader.h"
#include "core/util/input_error.h"

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace twinray;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    LoadReport report;
    SceneGeometry geometry;
    geometry.meshes.push_back(parse_obj(text, "fuzz.obj", report));
    clean_geometry(geometry, report);
  } catch (const InputError&) {
    // The documented way to reject bad input.
  }
  return 0;
}
