#pragma once
// `twinray trace`: one ray through several backends, every answer side by side (closest hit with t in
// decimal and hexadecimal, u, v, ids and normal; any-hit), the traversal work of counting backends and, for
// `bvh`, the nodes visited in order. The command that every failed grading check prints to replay its ray.

#include "core/geometry/ray.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace twinray::trace {

struct TraceSettings {
  std::string scene;                  // a scene name (harness/scenes/named_scene.h)
  std::vector<std::string> backends;  // at least one; answers are compared with the first
  Ray ray;
  bool visits = true;                 // print the bvh visit order
};

struct TraceReport {
  std::string text;
  nlohmann::json json;
  bool all_answered = true;  // false when a backend failed (a plugin crash, timeout or error)
  bool agree = true;         // every backend's answers match the first one's (hit_comparison.h's "identical")
};

// Throws InputError for a bad scene or plugin, std::invalid_argument for bad settings. A backend that fails
// while building or answering (a plugin that crashes) is reported in the text and JSON, not thrown.
TraceReport run_trace(const TraceSettings& settings);

}  // namespace twinray::trace
