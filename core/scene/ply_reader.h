#pragma once
// Stanford PLY reader: ascii, binary_little_endian and binary_big_endian.
//
// Reads the `vertex` element's x, y, z (any scalar type; other vertex properties are skipped) and the
// `face` element's `vertex_indices` (or `vertex_index`) list with any integer count and index types.
// Every other element and property, including list properties, is skipped by its declared layout.
// Polygons are split into a fan around their first corner (exact for convex polygons) and counted in
// LoadReport::polygons_triangulated; faces with fewer than three corners count as degenerate.

#include "core/geometry/scene_geometry.h"
#include "core/scene/scene.h"

#include <filesystem>
#include <string_view>

namespace twinray {

// Throws InputError for a malformed header ("line N"), truncated data, out-of-range indices or non-finite
// coordinates ("line N" in ascii files, "vertex N" / "face N" / "byte N" in binary ones). Declared element
// counts are checked against the file size before anything is allocated. The mesh is not cleaned (see
// geometry_cleanup.h). geom_id is left 0.
TriangleMesh read_ply(const std::filesystem::path& path, LoadReport& report);

// The same, from the file's bytes already in memory; `path` is only used in error messages.
TriangleMesh parse_ply(std::string_view bytes, const std::filesystem::path& path, LoadReport& report);

}  // namespace twinray
