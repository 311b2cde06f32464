#pragma once
// The scene as the plugin worker receives it: one contiguous block of the shared memory file, laid out as
// worker_protocol.h describes (GeometryBlobHeader, MeshRecords, spheres, then the arrays).

#include "core/geometry/scene_geometry.h"

#include <cstddef>

namespace twinray {

// Bytes the blob of `geometry` takes.
std::size_t geometry_blob_bytes(const SceneGeometry& geometry);

// Writes the blob into `destination` (geometry_blob_bytes(geometry) bytes, 64-byte aligned, zero-filled).
void write_geometry_blob(const SceneGeometry& geometry, void* destination);

}  // namespace twinray
