#pragma once
// The Embree 3 backends: `embree` (robust, the correctness reference) and `embree-fast` (the speed
// reference). They differ only in RTC_SCENE_FLAG_ROBUST; see docs/embree-backend.md.

#include "core/backend/backend.h"

#include <cstddef>
#include <memory>

namespace twinray {

// robust = true:  name() "embree",      RTC_SCENE_FLAG_ROBUST (watertight triangle test).
// robust = false: name() "embree-fast", default scene flags.
std::unique_ptr<Backend> make_embree_backend(bool robust);

// Embree-specific facts about a build, beyond BuildStats.
struct EmbreeBuildReport {
  std::size_t shared_meshes = 0;       // meshes whose vertex and index buffers Embree reads in place
  std::size_t padded_mesh_copies = 0;  // meshes whose positions were copied for lack of tail padding
};

// The report of an Embree backend built by make_embree_backend; nullptr for any other backend.
const EmbreeBuildReport* embree_build_report(const Backend& backend);

}  // namespace twinray
