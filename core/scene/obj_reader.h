#pragma once
// Wavefront OBJ reader for what a path tracer needs: vertex positions (`v`) and polygonal faces (`f`).
// Everything else (vt, vn, groups, objects, materials, lines, points) is read past; all objects of the file
// become one mesh. Polygons with more than three vertices are split into a fan around their first vertex,
// which is exact for convex (and star-shaped-from-the-first-vertex) polygons, the polygons OBJ exporters
// write; each one counts in LoadReport::polygons_triangulated.

#include "core/geometry/scene_geometry.h"
#include "core/scene/scene.h"

#include <filesystem>
#include <string_view>

namespace twinray {

// Throws InputError("file", "line N", ...) for a malformed statement, a non-finite or out-of-float-range
// coordinate, or a face index that is zero or out of range. The mesh is not cleaned (see geometry_cleanup.h):
// degenerate triangles are still in it. geom_id is left 0.
TriangleMesh read_obj(const std::filesystem::path& path, LoadReport& report);

// The same, from text already in memory; `path` is only used in error messages.
TriangleMesh parse_obj(std::string_view text, const std::filesystem::path& path, LoadReport& report);

}  // namespace twinray
