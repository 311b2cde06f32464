#pragma once
// Procedural scenes for the benchmark scale series (bench/, docs/benchmarks.md): four families of triangle
// meshes, each generated at any size so that build and traversal cost can be plotted against the triangle
// count N. Each family stresses a BVH differently:
//   sphere   a closed tessellated sphere: a well-behaved surface, the easy case;
//   soup     independent random triangles in a cube, smaller as N grows so that the depth complexity
//            stays about constant: measures pure scaling;
//   terrain  a height field: one large, mostly flat surface seen at a grazing angle;
//   hairball long thin randomly oriented needles in a ball: boxes overlap heavily, the hard case (needle
//            size shrinks with N so that the depth complexity, like the soup's, stays about constant).
//
// Deterministic: the same (family, N, seed) gives bit-identical geometry (core/sampling/rng.h, plain IEEE
// float). Results satisfy the SceneGeometry invariants (no degenerate triangle, spare vertex capacity for
// Embree). The triangle count is close to, not exactly, the requested one (tessellations come in steps);
// callers report the actual count.

#include "core/geometry/scene_geometry.h"
#include "core/scene/scene.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace twinray {

enum class BenchFamily { Sphere, Soup, Terrain, Hairball };

inline constexpr BenchFamily kAllBenchFamilies[] = {BenchFamily::Sphere, BenchFamily::Soup, BenchFamily::Terrain,
                                                     BenchFamily::Hairball};

std::string_view to_string(BenchFamily family);
std::optional<BenchFamily> parse_bench_family(std::string_view name);

// One mesh (geom_id 0) of about `triangles` triangles (at least a few dozen).
SceneGeometry bench_sphere(std::size_t triangles);
SceneGeometry bench_soup(std::size_t triangles, std::uint64_t seed);
SceneGeometry bench_terrain(std::size_t triangles, std::uint64_t seed);
SceneGeometry bench_hairball(std::size_t triangles, std::uint64_t seed);
SceneGeometry bench_geometry(BenchFamily family, std::size_t triangles, std::uint64_t seed);

// A complete scene around benchmark geometry: one white diffuse material, no emitters, no environment,
// and the default framing camera (core/scene/mesh_scene.h) at width x height. Ray generators aim shadow
// rays at random points of the scene box when there are no emitters.
Scene bench_scene(SceneGeometry geometry, const std::string& name, int width = 512, int height = 512);

}  // namespace twinray
