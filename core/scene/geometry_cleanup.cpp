#include "core/scene/geometry_cleanup.h"

#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace twinray {
namespace {

bool is_finite(const glm::vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

}  // namespace

bool is_degenerate_triangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  if (a == b || b == c || a == c) return true;
  const glm::dvec3 e1 = glm::dvec3(b) - glm::dvec3(a);
  const glm::dvec3 e2 = glm::dvec3(c) - glm::dvec3(a);
  const glm::dvec3 n(e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x);
  return n.x == 0.0 && n.y == 0.0 && n.z == 0.0;
}

bool is_degenerate_triangle(const TriangleMesh& mesh, const glm::uvec3& tri) {
  if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) return true;
  return is_degenerate_triangle(mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]);
}

void remove_invalid_triangles(TriangleMesh& mesh, LoadReport& report) {
  const std::size_t vertex_count = mesh.positions.size();
  std::size_t kept = 0;
  for (std::size_t t = 0; t < mesh.indices.size(); ++t) {
    const glm::uvec3 tri = mesh.indices[t];
    if (tri[0] >= vertex_count || tri[1] >= vertex_count || tri[2] >= vertex_count)
      throw std::invalid_argument("triangle " + std::to_string(t) + " of geometry " + std::to_string(mesh.geom_id) +
                                  " has a vertex index out of range (" + std::to_string(vertex_count) +
                                  " vertices)");
    if (!is_finite(mesh.positions[tri[0]]) || !is_finite(mesh.positions[tri[1]]) ||
        !is_finite(mesh.positions[tri[2]])) {
      ++report.nonfinite_triangles;
      continue;
    }
    if (is_degenerate_triangle(mesh, tri)) {
      ++report.degenerate_triangles;
      continue;
    }
    mesh.indices[kept++] = tri;
  }
  mesh.indices.resize(kept);
}

void clean_geometry(SceneGeometry& geometry, LoadReport& report) {
  for (TriangleMesh& mesh : geometry.meshes) {
    remove_invalid_triangles(mesh, report);
    ensure_vertex_padding(mesh.positions);
  }
  // An empty mesh would be a geometry with no primitives, which some backends reject; its shape still keeps
  // its geometry id in Scene::shapes, the id is simply never hit.
  std::erase_if(geometry.meshes, [](const TriangleMesh& m) { return m.indices.empty(); });
}

void ensure_vertex_padding(std::vector<glm::vec3>& positions) {
  if (positions.capacity() <= positions.size()) positions.reserve(positions.size() + 1);
}

}  // namespace twinray
