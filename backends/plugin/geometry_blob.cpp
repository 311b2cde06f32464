#include "backends/plugin/geometry_blob.h"
#include "backends/plugin/plugin_hit.h"

#include "backends/plugin/worker_protocol.h"

#include <cstdint>
#include <cstring>

namespace twinray {

namespace {

using plugin_worker::GeometryBlobHeader;
using plugin_worker::MeshRecord;

constexpr std::size_t kAlignment = 64;
// After the last vertex: the ABI promises 4 readable bytes; 16 cover any SIMD load of a vertex.
constexpr std::size_t kPositionsPadding = 16;

std::size_t align(std::size_t n) { return (n + kAlignment - 1) / kAlignment * kAlignment; }

// Walks the layout once for sizing and once for writing, so the two can never disagree.
template <typename Visit>
std::size_t lay_out(const SceneGeometry& g, Visit&& visit) {
  std::size_t at = align(sizeof(GeometryBlobHeader) + g.meshes.size() * sizeof(MeshRecord) +
                         g.spheres.size() * sizeof(twinray_sphere));
  for (std::size_t m = 0; m < g.meshes.size(); ++m) {
    const TriangleMesh& mesh = g.meshes[m];
    const std::size_t positions = at;
    at = align(at + mesh.positions.size() * sizeof(glm::vec3) + kPositionsPadding);
    const std::size_t indices = at;
    at = align(at + mesh.indices.size() * sizeof(glm::uvec3));
    visit(m, positions, indices);
  }
  return at;
}

}  // namespace

std::size_t geometry_blob_bytes(const SceneGeometry& geometry) {
  return lay_out(geometry, [](std::size_t, std::size_t, std::size_t) {});
}

void write_geometry_blob(const SceneGeometry& g, void* destination) {
  auto* base = static_cast<unsigned char*>(destination);
  GeometryBlobHeader header;
  header.mesh_count = g.meshes.size();
  header.sphere_count = g.spheres.size();
  header.geom_id_end = g.geom_id_end();
  std::memcpy(base, &header, sizeof header);
  auto* records = base + sizeof(GeometryBlobHeader);
  auto* spheres = records + g.meshes.size() * sizeof(MeshRecord);

  lay_out(g, [&](std::size_t m, std::size_t positions, std::size_t indices) {
    const TriangleMesh& mesh = g.meshes[m];
    MeshRecord r;
    r.geom_id = mesh.geom_id;
    r.vertex_count = mesh.positions.size();
    r.positions_offset = positions;
    r.triangle_count = mesh.indices.size();
    r.indices_offset = indices;
    std::memcpy(records + m * sizeof(MeshRecord), &r, sizeof r);
    if (!mesh.positions.empty()) std::memcpy(base + positions, mesh.positions.data(), mesh.positions.size() * sizeof(glm::vec3));
    if (!mesh.indices.empty()) std::memcpy(base + indices, mesh.indices.data(), mesh.indices.size() * sizeof(glm::uvec3));
  });
  for (std::size_t k = 0; k < g.spheres.size(); ++k) {
    const twinray_sphere ps = to_plugin_sphere(g.spheres[k]);
    std::memcpy(spheres + k * sizeof(twinray_sphere), &ps, sizeof ps);
  }
}

}  // namespace twinray
