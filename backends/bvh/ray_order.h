#pragma once
// The order in which a batch's rays are traced: by the Morton code of their origins.
//
// Incoherent rays (diffuse bounces, shadow rays) make traversal wait on cache misses: each ray walks its own
// path down the tree. Rays that start close together, though, walk the same nodes near their origin (every
// node whose box contains the origin is entered) and test the same leaves. Tracing a batch in the order of
// a space-filling curve through the origins lets each ray find the nodes its predecessor just loaded
// (Pharr et al., "Rendering complex scenes with memory-coherent ray tracing", SIGGRAPH 1997; Moon et al.,
// "Cache-oblivious ray reordering", TOG 2010; wavefront path tracers sort their rays for the same reason).
// The order changes only the speed: every ray is still traced on its own and its answer written to its
// own slot.

#include "core/geometry/bounds.h"
#include "core/geometry/ray.h"

#include <cstdint>
#include <span>
#include <vector>

namespace twinray {

// Indices of `rays` sorted by the 30-bit Morton code of their origins within `bounds` (origins outside
// are clamped to it); ties keep the input order, so the permutation is deterministic.
std::vector<std::uint32_t> morton_ray_order(std::span<const Ray> rays, const Bounds3& bounds);

}  // namespace twinray
