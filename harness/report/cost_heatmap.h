#pragma once
// Per-pixel traversal cost: one camera ray through each pixel centre, traced closest-hit by a backend
// that counts its traversal (bvh), recording nodes visited and primitives tested. Independent of the
// renderer, so it shows the acceleration structure alone.

#include "core/backend/backend.h"
#include "core/image/image.h"
#include "core/scene/scene.h"

namespace twinray::report {

struct CostImages {
  Image nodes;       // 1 channel: nodes visited per pixel
  Image primitives;  // 1 channel: primitives tested per pixel
  double mean_nodes = 0.0, mean_primitives = 0.0;
};

// `backend` must be built on scene.geometry and count traversal (traits().counts_traversal), else
// std::invalid_argument. Resolution: the scene's camera.
CostImages traversal_cost_images(const Scene& scene, const Backend& backend);

}  // namespace twinray::report
