#pragma once
// Establishes the SceneGeometry invariants (core/geometry/scene_geometry.h) on loaded or programmatic
// geometry: triangles with a non-finite vertex and degenerate triangles are dropped and counted, and
// every vertex buffer gets the spare capacity Embree's 16-byte vertex loads need.

#include "core/geometry/scene_geometry.h"
#include "core/scene/scene.h"

namespace twinray {

// A triangle is degenerate when two of its indices are equal, two of its vertices are at the same position,
// or the cross product of its edges, evaluated in double precision, is exactly zero.
//
// Why double: in float, the edge vectors of a thin sliver far from the origin lose most of their bits to
// cancellation and the cross product can round to exactly zero although the triangle has area; dropping it
// would punch a hole in the surface. The products of two float differences are (almost always) exact in
// double, so only truly collinear triangles come out zero. Near-degenerate triangles stay: the
// intersection routines are watertight for them, we only remove the ones no ray can ever hit.
bool is_degenerate_triangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c);
bool is_degenerate_triangle(const TriangleMesh& mesh, const glm::uvec3& tri);

// Drops triangles that have a non-finite vertex (counted in report.nonfinite_triangles) and degenerate ones
// (report.degenerate_triangles), keeping the order of the rest. Vertices are not renumbered.
// Throws std::invalid_argument for an index out of range: that is a programming error, not bad input
// (the file readers reject such indices with the file location first).
void remove_invalid_triangles(TriangleMesh& mesh, LoadReport& report);

// remove_invalid_triangles on every mesh, drops meshes left without triangles, and pads vertex buffers.
// Spheres are left alone (their validity is checked where they are created).
void clean_geometry(SceneGeometry& geometry, LoadReport& report);

// Guarantees positions.capacity() > positions.size() (the Embree padding invariant).
void ensure_vertex_padding(std::vector<glm::vec3>& positions);

}  // namespace twinray
