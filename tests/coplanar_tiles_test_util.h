#pragma once
// Overlapping coplanar tiles and rays from above them, shared by the tie tests of bvh and bvh8
// (test_bvh_vs_brute.cpp, test_bvh_tie_boxes.cpp): every crossing of two tiles is a tie at one rounded t,
// between triangles that the builders put in different leaves, whose flat boxes the ray enters exactly there.

#include "core/geometry/ray.h"
#include "core/sampling/rng.h"

#include <glm/vec3.hpp>

#include <vector>

namespace twinray::test {

// `count` triangles at z = 0.3, three corners each, centres uniform in [-1, 1]^2; large enough to overlap.
inline std::vector<glm::vec3> overlapping_tile_corners(Rng& rng, int count) {
  std::vector<glm::vec3> corners;
  corners.reserve(3 * static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) {
    const glm::vec3 c(2.0f * rng.next_float() - 1.0f, 2.0f * rng.next_float() - 1.0f, 0.3f);
    corners.push_back(c + glm::vec3(-0.6f * rng.next_float() - 0.2f, -0.3f, 0.0f));
    corners.push_back(c + glm::vec3(0.6f * rng.next_float() + 0.2f, -0.3f, 0.0f));
    corners.push_back(c + glm::vec3(0.0f, 0.6f * rng.next_float() + 0.2f, 0.0f));
  }
  return corners;
}

// A ray from above the tiles, pointing down at a slant, most of them crossing several tiles.
inline Ray ray_towards_tiles(Rng& rng) {
  Ray ray;
  ray.org = {2.0f * rng.next_float() - 1.0f, 2.0f * rng.next_float() - 1.0f, 1.0f + rng.next_float()};
  ray.dir = {0.7f * rng.next_float() - 0.35f, 0.7f * rng.next_float() - 0.35f, -0.5f - rng.next_float()};
  return ray;
}

}  // namespace twinray::test
