#pragma once
// Procedural test geometry for unit tests and benchmarks. Every generator is deterministic: the same
// arguments (and seed) give bit-identical geometry on every run and platform, because all randomness comes
// from core/sampling/rng.h and the arithmetic is plain IEEE float.
//
// The results satisfy the SceneGeometry invariants (finite vertices, in-range indices, no degenerate
// triangle, spare vertex capacity for Embree), so they can be handed to any backend directly.
// Geometry ids are 0, 1, 2, ... in the order documented for each function.

#include "core/geometry/scene_geometry.h"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>

namespace twinray {

// A closed, watertight sphere: an icosahedron whose faces are split `subdivisions` times (4^s * 20
// triangles), vertices projected onto the sphere. Vertices are shared between faces (each edge is used by
// exactly two triangles, in opposite directions) and every face winds counter-clockwise seen from outside,
// so the geometric normal points outward. One mesh, geom_id 0.
SceneGeometry tessellated_sphere(const glm::vec3& center, float radius, int subdivisions);

// n independent triangles with vertices in [-1, 1]^3: a random center and three vertices within 0.15 of
// it, so the triangles overlap, intersect each other and vary in size and orientation. One mesh, geom_id 0.
SceneGeometry random_triangle_soup(std::size_t n, std::uint64_t seed);

// A planar grid of nx * ny unit squares in the z = 0 plane, vertex (i, j, 0) for 0 <= i <= nx, 0 <= j <= ny,
// two triangles per square, counter-clockwise seen from +z. The diagonal alternates in a checkerboard so
// that vertices of valence 4 and 8 both occur. Integer coordinates make rays through edges and vertices
// exactly representable. One mesh, geom_id 0; triangle 2 * (j * nx + i) + {0, 1} lies in square (i, j).
SceneGeometry grid_mesh(int nx, int ny);

// n spheres with centers in [-1, 1]^3 and radii in [0.02, 0.12]; sphere k has geom_id k.
SceneGeometry random_spheres(std::size_t n, std::uint64_t seed);

// Spheres mixed with triangles, ids interleaved the way a scene file would number them:
// geom_id 0: a triangle soup (n_triangles), 1 .. n_spheres: spheres, then a tessellated sphere (subdivision
// 3, centered at the origin, radius 0.5) as the last geometry.
SceneGeometry mixed_spheres_and_triangles(std::size_t n_spheres, std::size_t n_triangles, std::uint64_t seed);

}  // namespace twinray
