#include "backends/embree/embree_triangle_geometry.h"

#include <glm/vec3.hpp>

namespace twinray {

static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "positions are shared with Embree as packed FLOAT3");
static_assert(sizeof(glm::uvec3) == 3 * sizeof(unsigned), "indices are shared with Embree as packed UINT3");

EmbreeTriangleGeometry create_triangle_geometry(RTCDevice device, const TriangleMesh& mesh) {
  EmbreeTriangleGeometry result;
  result.geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  if (result.geometry == nullptr) return result;  // the device's error callback has the reason

  const glm::vec3* positions = mesh.positions.data();
  // One spare vertex is the 4 readable bytes Embree needs, and more than enough (12 >= 4).
  if (mesh.positions.capacity() <= mesh.positions.size()) {
    result.padded_positions.reserve(mesh.positions.size() + 1);
    result.padded_positions.assign(mesh.positions.begin(), mesh.positions.end());
    positions = result.padded_positions.data();
  }
  rtcSetSharedGeometryBuffer(result.geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, positions, 0,
                             sizeof(glm::vec3), mesh.positions.size());
  rtcSetSharedGeometryBuffer(result.geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh.indices.data(), 0,
                             sizeof(glm::uvec3), mesh.indices.size());
  rtcSetGeometryBuildQuality(result.geometry, RTC_BUILD_QUALITY_MEDIUM);
  rtcCommitGeometry(result.geometry);
  return result;
}

}  // namespace twinray
