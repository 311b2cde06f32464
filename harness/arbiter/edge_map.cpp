#include "harness/arbiter/edge_map.h"

#include <algorithm>
#include <bit>

namespace twinray::arbiter {

namespace {

// The side of edge (a, b) on which p lies, seen along dir: the sign of dir . ((b - a) x (p - a)). Double is
// enough: this classifies neighbours for a tolerance, it does not decide a hit.
int side(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& p, const glm::dvec3& dir) {
  const glm::dvec3 e = b - a, q = p - a;
  const glm::dvec3 n{e.y * q.z - e.z * q.y, e.z * q.x - e.x * q.z, e.x * q.y - e.y * q.x};
  const double s = dir.x * n.x + dir.y * n.y + dir.z * n.z;
  return s > 0.0 ? 1 : (s < 0.0 ? -1 : 0);
}

}  // namespace

std::array<std::uint32_t, 6> EdgeMap::key_of(const glm::vec3& a, const glm::vec3& b) {
  const std::array<std::uint32_t, 3> ka{std::bit_cast<std::uint32_t>(a.x), std::bit_cast<std::uint32_t>(a.y),
                                        std::bit_cast<std::uint32_t>(a.z)};
  const std::array<std::uint32_t, 3> kb{std::bit_cast<std::uint32_t>(b.x), std::bit_cast<std::uint32_t>(b.y),
                                        std::bit_cast<std::uint32_t>(b.z)};
  const bool a_first = ka <= kb;
  const auto& lo = a_first ? ka : kb;
  const auto& hi = a_first ? kb : ka;
  return {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
}

EdgeMap::EdgeMap(const SceneGeometry& geometry) {
  entries_.reserve(3 * geometry.triangle_count());
  for (const TriangleMesh& mesh : geometry.meshes) {
    for (std::size_t i = 0; i < mesh.indices.size(); ++i) {
      const glm::uvec3& tri = mesh.indices[i];
      for (int k = 0; k < 3; ++k) {
        const glm::vec3& a = mesh.positions[tri[k]];
        const glm::vec3& b = mesh.positions[tri[(k + 1) % 3]];
        const glm::vec3& c = mesh.positions[tri[(k + 2) % 3]];
        entries_.push_back({key_of(a, b), mesh.geom_id, static_cast<std::uint32_t>(i), c});
      }
    }
  }
  std::sort(entries_.begin(), entries_.end(), [](const Entry& x, const Entry& y) { return x.key < y.key; });
}

bool EdgeMap::escapable(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, std::uint32_t self_geom,
                        std::uint32_t self_prim, const glm::dvec3& dir) const {
  const auto key = key_of(a, b);
  const auto range = std::equal_range(entries_.begin(), entries_.end(), Entry{key, 0, 0, {}},
                                      [](const Entry& x, const Entry& y) { return x.key < y.key; });
  const glm::dvec3 da(a), db(b);
  const int own = side(da, db, glm::dvec3(c), dir);
  for (auto it = range.first; it != range.second; ++it) {
    if (it->geom_id == self_geom && it->prim_id == self_prim) continue;
    if (own * side(da, db, glm::dvec3(it->third), dir) < 0) return false;  // the surface continues across
  }
  return true;
}

}  // namespace twinray::arbiter
