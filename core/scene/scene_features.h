#pragma once
// What a scene needs, and therefore what twinray builds for it and what it leaves out.
// `twinray info` prints this list; renders report it in their summary.

#include "core/scene/scene.h"

#include <string>
#include <vector>

namespace twinray {

struct Feature {
  std::string name;    // e.g. "sphere geometry"
  bool used = false;   // false: left out
  std::string detail;  // why, or how much
};

std::vector<Feature> scene_features(const Scene& scene);

}  // namespace twinray
