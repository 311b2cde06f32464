#pragma once
// A triangle mesh as an Embree triangle geometry that reads twinray's buffers in place.
//
// The vertex buffer is shared as RTC_FORMAT_FLOAT3 with a 12-byte stride over TriangleMesh::positions and
// the index buffer as RTC_FORMAT_UINT3 over TriangleMesh::indices: no copy. Embree loads vertices with
// 16-byte SIMD reads, so the 4 bytes after the last vertex must be readable; the loaders guarantee that
// with positions.capacity() > positions.size() (scene_geometry.h). A mesh built by other means may not
// honour it: then, and only then, the positions are copied into a buffer with room to spare.

#include "core/geometry/scene_geometry.h"

#include <embree3/rtcore.h>
#include <glm/vec3.hpp>

#include <vector>

namespace twinray {

struct EmbreeTriangleGeometry {
  RTCGeometry geometry = nullptr;            // committed; the caller attaches and releases it
  // Empty when the mesh's own positions are shared. Embree points into its heap block, which a move of
  // the vector keeps in place: move it, never copy it.
  std::vector<glm::vec3> padded_positions;
};

// `mesh` must outlive the geometry.
EmbreeTriangleGeometry create_triangle_geometry(RTCDevice device, const TriangleMesh& mesh);

}  // namespace twinray
