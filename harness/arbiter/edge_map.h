#pragma once
// Which triangles share an edge, by vertex *position* (bit-identical coordinates), across meshes: the
// neighbourhood a watertight intersector must keep closed. (Meshes need not share vertex indices to be
// closed: the integer box of the stress catalogue has faces with their own vertices.)
//
// The arbiter asks one question of it: if the ray were moved across an edge of a triangle it crosses, would
// it enter a neighbouring triangle (the surface continues: a watertight backend may not lose the
// crossing), or leave the surface (a mesh boundary, or a silhouette edge whose neighbour lies on the same
// side as seen along the ray)?

#include "core/geometry/scene_geometry.h"

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace twinray::arbiter {

class EdgeMap {
 public:
  explicit EdgeMap(const SceneGeometry& geometry);

  // True when moving the ray's line across edge (a, b) of triangle (a, b, c) leaves the surface: no triangle
  // shares the edge, or every one that does lies on the same side of it as c, or is seen edge-on, when
  // projected along `dir`. `self` names the triangle, so that it is not its own neighbour.
  bool escapable(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, std::uint32_t self_geom,
                 std::uint32_t self_prim, const glm::dvec3& dir) const;

 private:
  struct Entry {
    std::array<std::uint32_t, 6> key;  // the two endpoints' bits, lower endpoint first
    std::uint32_t geom_id, prim_id;
    glm::vec3 third;                   // the triangle's vertex off the edge
  };
  static std::array<std::uint32_t, 6> key_of(const glm::vec3& a, const glm::vec3& b);
  std::vector<Entry> entries_;  // sorted by key
};

}  // namespace twinray::arbiter
