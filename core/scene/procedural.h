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
#include <optional>

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

// A soup of n triangles (random_triangle_soup's kind) in which every fourth, from index 1, is a thin but valid
// sliver: its apex lies on a point of its first edge lifted off it by the edge's length over an aspect ratio
// log-uniform in [1e3, 1e7] (index 1: 1e7). Every other triangle is numbered after a sliver, so a builder
// that drops "degenerate" slivers and numbers the rest 0, 1, 2, ... names them wrong. One mesh, geom_id 0.
SceneGeometry sliver_soup(std::size_t n, std::uint64_t seed);

// n clusters of `per_cluster` (1..32) different triangles whose bounding boxes are all one cube: every
// triangle's vertices are three corners of the cube [c - r, c + r]^3 that differ in every axis, so the box of
// each (and its centre, the centroid a builder bins by) is exactly the cube and its centre c. No split by box
// centres separates a cluster, so a builder keeps it in one leaf (or splits it by count): the scene that
// shows a leaf's primitive count stored in too few bits. Centres lie on a grid of 2^-6 in [-1, 1]^3 and r
// is a multiple of 2^-6, so c +- r is exact. One mesh, geom_id 0.
SceneGeometry coincident_boxes(std::size_t n, int per_cluster, std::uint64_t seed);

// Nested levels around the origin, the scene that makes a SAH tree deep along one ray: level j (0 ..
// levels - 1, at most kMaxNestLevels) holds triangles at distance about s_j = 2^(36 - 3j/2) from the origin,
// in the cone of directions around the diagonal (1, 1, 1), and the same again mirrored in x (around
// (-1, 1, 1)). Levels shrink geometrically toward the origin, so a SAH or midpoint builder peels
// them off one by one: the box of the inner levels contains the origin and the outer level's box lies
// farther out, so a ray from the origin enters the inner box first (at t = tmin) and the level's box later.
// A traversal that visits the nearer child first therefore keeps one pending entry per level, and the
// closest hit (the innermost level in the ray's direction) is among the last entries pushed. Level j holds
// ceil(1.15^(levels - 1 - j)) triangles: the outer levels hold more primitives than all the levels inside
// them together weigh in SAH cost, which is what keeps a SAH builder from grouping several levels per split
// (with equal counts it groups about three). The outer levels' many triangles give every ray into a cone an
// early hit, where an any-hit query stops; so each cone has a tunnel, directions within 0.1 radian of its
// axis, that only the innermost three levels cross, each with one more (small) triangle across it: rays
// along it hit nothing before the innermost levels. The scales stay within [2^-36, 2^36], where every
// product of three coordinates a float triangle test forms (with a unit direction) is a normal float, with a
// margin. One mesh, geom_id 0.
inline constexpr int kMaxNestLevels = 49;
// `cone`, given, replaces the two cones by one around it (components +-1): around (-1, -1, -1) every inner
// level lies on the high side of every split plane, the child a traversal that pushes left then right visits
// first (see docs/grading.md, "The deep-tree scene").
// `cap` adds, after every other triangle, one triangle across each cone's tunnel far beyond the outermost
// level (at 2^38 along the axis, its vertices within 2^39: every product of three coordinates is still a
// normal float), and keeps the innermost levels' other triangles out of the tunnel too: a ray along the
// tunnel that passes their small triangles across it hits the cap last of all, and a traversal pushes the
// cap's subtree first. A stack that keeps the newest entries when full (a ring that
// overwrites the oldest) loses it, where one that drops new entries does not.
SceneGeometry nested_levels(int levels, std::uint64_t seed, std::optional<glm::vec3> cone = std::nullopt,
                            bool cap = false);

}  // namespace twinray
