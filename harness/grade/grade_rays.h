#pragma once
// The ray sets of the grading checks that crosscheck's kinds (harness/crosscheck/ray_generation.h) do not
// cover. Every set is a pure function of its inputs and seed, so a suite shoots the same rays on every run.

#include "core/backend/backend.h"
#include "core/scene/scene.h"
#include "harness/crosscheck/ray_kinds.h"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace twinray::grade {

// Camera rays for an image: through the pixel centres of the scene's camera resized (same field of view and
// aspect) to about `count` pixels, row by row from the top, so ray i lands in pixel i.
struct PixelRays {
  int width = 0, height = 0;
  std::vector<Ray> rays;
};
PixelRays camera_pixel_rays(const Scene& scene, std::size_t count);

// `count` rays of one kind: camera rays are pixel-centre rays (above); the others come from crosscheck's
// generator, surface points found with `hit_source` (a built-in backend, never the plugin).
std::vector<Ray> kind_rays(crosscheck::RayKind kind, const Scene& scene, const Backend& hit_source, std::size_t count,
                           std::uint64_t seed);

// The relative distance of the ray-interval variants from the surface they straddle: ten times crosscheck's
// t tolerance (kRelT), so that no correct intersector's rounding puts a hit on the wrong side.
inline constexpr float kIntervalMargin = 1e-3f;

// Up to four variants of every ray that hits (at t): [tmin, t(1-m)] and [t(1+m), tmax] must not report that
// surface, [tmin, t(1+m)] and [t(1-m), tmax] must. Rays that miss give none.
std::vector<Ray> interval_rays(std::span<const Ray> rays, std::span<const Hit> hits);

// crosscheck::axis_aligned_rays (harness/crosscheck/axis_rays.h), the same rays: also crosscheck's `axis` kind.
std::vector<Ray> axis_aligned_rays(const Scene& scene, std::size_t count, std::uint64_t seed);

// Rays that must hit a closed mesh: from `origin` (inside; default the centre of the bounds) in random
// directions and exactly through vertices and edge midpoints, and from outside straight at vertices along
// their (area-weighted) vertex normals, which cross the surface there rather than slide along a face.
std::vector<Ray> watertight_rays(const Scene& scene, std::size_t count, std::uint64_t seed,
                                 std::optional<glm::vec3> origin);

// Rays at the scene's spheres: from outside at the disc (from 2 to 10 radii away, and from 2,000 to 20,000,
// where the textbook quadratic b^2 - 4ac in float loses r^2 to cancellation), from inside, near-tangent
// (offset 0.99 r and 1.01 r), tangent and clear misses; then count / 8 segments that start and end inside a
// ball (tmax 0.4 r from within 0.5 r of its centre), which hit nothing of their sphere.
std::vector<Ray> sphere_rays(const Scene& scene, std::size_t count, std::uint64_t seed);

// Rays at random interior points of random triangles (barycentrics at least 0.1 from every edge), from
// random points around the scene: on duplicated geometry every one is an exact tie.
std::vector<Ray> tie_rays(const Scene& scene, std::size_t count, std::uint64_t seed);

// Rays from `origin` (default the origin of coordinates) at interior points of the scene's triangles, for
// the deep-tree check: the triangles are grouped by the binary order of magnitude of their distance from
// `origin` (floor(log2)), and every ray picks a group uniformly, then a triangle in it, so that the few
// triangles of the innermost levels of a nested scene (procedural:nest) are aimed at as often as the many
// of the outer ones. Closest and any-hit.
std::vector<Ray> deep_tree_rays(const Scene& scene, std::size_t count, std::uint64_t seed,
                                std::optional<glm::vec3> origin);

}  // namespace twinray::grade
