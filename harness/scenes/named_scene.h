#pragma once
// Scenes by name: everything a command line can point at, so that a scene a grading suite shoots at can be
// named again in a `twinray trace` line and rebuilt bit for bit.
//
//   path/to/scene.json, mesh.obj, mesh.ply   a file (load_scene); relative to `base` when not absolute
//   $TWINRAY_SHARED/data/meshes/bunny.obj     a file in the shared data folder (core/scene/shared_data.h)
//   procedural:KIND[:ARG]...                  geometry generated in memory (procedural_scene_kinds() lists
//                                             them), wrapped in a scene whose camera frames it
//
// Procedural scenes are deterministic (core/scene/procedural.h): the same name gives the same vertices on
// every run and machine.

#include "core/scene/scene.h"

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace twinray {

inline constexpr std::string_view kProceduralPrefix = "procedural:";

struct ProceduralKind {
  std::string name;       // e.g. "soup"
  std::string arguments;  // e.g. "N:SEED"
  std::string summary;    // one line
};
const std::vector<ProceduralKind>& procedural_scene_kinds();

bool is_procedural_scene_name(std::string_view name);

// Loads a scene by name (see above). Throws InputError naming the scene (a bad procedural name or argument
// included).
Scene load_named_scene(std::string_view name, const std::filesystem::path& base = {});

// The name under which a file scene is found again from any folder (absolute path); procedural names and
// $TWINRAY_SHARED names are returned as they are.
std::string portable_scene_name(std::string_view name, const std::filesystem::path& base = {});

}  // namespace twinray
