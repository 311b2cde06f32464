#pragma once
// Deterministic ray sets for cross-checks, benchmarks and stress tests.
//
// Rays that start on surfaces (diffuse, shadow) need first hits; they are found with `hit_source`, one
// backend chosen by the caller, so every backend under test then traces exactly the same rays.

#include "harness/crosscheck/ray_kinds.h"
#include "core/backend/backend.h"
#include "core/scene/scene.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace twinray::crosscheck {

std::vector<Ray> generate_rays(RayKind kind, const Scene& scene, const Backend& hit_source, std::size_t count,
                               std::uint64_t seed);

}  // namespace twinray::crosscheck
