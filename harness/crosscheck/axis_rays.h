#pragma once
// Rays with exactly zero direction components, of both signs (crosscheck's `axis` kind, and the grader's
// axis-aligned checks): along the axes, in the coordinate planes, from origins exactly on the faces of the
// scene's bounding box pointing inward, and (scenes with triangles) along the axes and in the coordinate
// planes through a vertex: the origin has the vertex's coordinate in every axis the direction is zero in, so
// the ray runs exactly in the planes of every box that has the vertex on a face. A slab test that divides by
// a zero component gets +-inf, and 0 * inf = NaN where the origin lies in a box's plane: such a test must not
// lose the box, nor take -0 for +0.

#include "core/geometry/ray.h"
#include "core/scene/scene.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace twinray::crosscheck {

// `count` rays, a pure function of the scene and the seed; the six sub-kinds in turn (four without vertices).
std::vector<Ray> axis_aligned_rays(const Scene& scene, std::size_t count, std::uint64_t seed);

}  // namespace twinray::crosscheck
