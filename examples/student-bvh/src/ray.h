#pragma once
// A ray and the record of a hit.

#include "vec3.h"

#include <cstdint>
#include <limits>

struct Ray {
  Vec3 point;  // origin
  Vec3 dir;    // direction; NOT normalised: t is measured in units of |dir|
  // A hit counts when dist_bounds[0] <= t <= dist_bounds[1] (closed at both ends).
  float dist_bounds[2] = {0.0f, std::numeric_limits<float>::infinity()};

  Vec3 at(float t) const { return point + dir * t; }
};

// Ids of "nothing hit".
constexpr std::uint32_t kNoId = 0xFFFFFFFFu;

struct Trace {
  bool hit = false;
  float distance = std::numeric_limits<float>::infinity();  // t of the hit
  float u = 0.0f, v = 0.0f;  // triangles: hit point = (1-u-v) p0 + u p1 + v p2; spheres: see primitives.h
  Vec3 normal;               // unit geometric normal, never flipped toward the ray
  std::uint32_t geom_id = kNoId, prim_id = kNoId;

  // The closer of two traces. On equal distance the lower (geom_id, prim_id) wins, so the answer does not
  // depend on the order in which your traversal meets the primitives.
  static Trace closer(const Trace& a, const Trace& b) {
    if (!a.hit) return b;
    if (!b.hit) return a;
    if (a.distance != b.distance) return a.distance < b.distance ? a : b;
    if (a.geom_id != b.geom_id) return a.geom_id < b.geom_id ? a : b;
    return a.prim_id <= b.prim_id ? a : b;
  }
};

// What a query did, for twinray's statistics (optional: see plugin.cpp).
struct TraversalStats {
  std::uint64_t nodes_visited = 0;      // nodes whose box you tested
  std::uint64_t primitives_tested = 0;  // primitives whose hit() you called
};
