// libFuzzer target: the PLY reader (ascii and both binary byte orders), followed by the geometry cleanup.
// Contract under test: any byte string either parses into a mesh satisfying the SceneGeometry invariants
// or throws InputError; declared element counts never cause an allocation larger than the input warrants.

#include "core/scene/geometry_cleanup.h"
#include "core/scene/ply_reader.h"
#include "core/util/input_error.h"

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace twinray;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    LoadReport report;
    SceneGeometry geometry;
    geometry.meshes.push_back(parse_ply(bytes, "fuzz.ply", report));
    clean_geometry(geometry, report);
  } catch (const InputError&) {
  }
  return 0;
}
