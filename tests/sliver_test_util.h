#pragma once
// Thin triangles in random orientations, each shot through random interior points at chosen angles above its
// plane: the rays on which a float t loses digits (issue 11). The refinement tests draw their sets from here,
// each with its own ranges.

#include "core/geometry/ray.h"
#include "core/geometry/scene_geometry.h"
#include "core/sampling/rng.h"
#include "core/scene/geometry_cleanup.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <utility>
#include <vector>

namespace twinray::test {

struct SliverSet {
  SceneGeometry geometry;
  std::vector<Ray> rays;
};

struct SliverSetParams {
  int triangles = 64;
  int rays_per_triangle = 24;
  double log10_aspect_min = 2.0, log10_aspect_span = 3.0;  // aspect 10^(min + span r)
  double base_extent = 2.0;                                  // first vertex in [-extent, extent]^3
  // Degrees above the triangle's plane, drawn from the generator.
  std::function<double(Rng&)> degrees = [](Rng& rng) { return 1e-4 * std::pow(1e4, static_cast<double>(rng.next_float())); };
  double distance_min = 0.2, distance_span = 1.0;  // origin at target - (min + span r) d
  // Scales the (unit) direction when set, so that t is not a distance; drawn last.
  std::function<double(Rng&)> direction_scale;
};

inline glm::vec3 to_float(const glm::dvec3& v) {
  return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
}

inline SliverSet sliver_set(std::uint64_t seed, const SliverSetParams& params) {
  SliverSet s;
  Rng rng(seed, 0);
  TriangleMesh mesh;
  const auto sym = [&rng] { return 2.0 * rng.next_float() - 1.0; };
  for (int k = 0; k < params.triangles; ++k) {
    const double aspect = std::pow(10.0, params.log10_aspect_min + params.log10_aspect_span * rng.next_float());
    const glm::dvec3 n = glm::normalize(glm::dvec3(sym(), sym(), sym() + 1e-3));
    const glm::dvec3 along = glm::normalize(glm::cross(n, glm::dvec3(sym(), sym(), sym()) + glm::dvec3(1e-3)));
    const glm::dvec3 across = glm::cross(n, along);
    const glm::dvec3 base = params.base_extent * glm::dvec3(sym(), sym(), sym());
    const glm::dvec3 p[3] = {base, base + along, base + 0.5 * along + across / aspect};
    const auto first = static_cast<std::uint32_t>(mesh.positions.size());
    for (const glm::dvec3& v : p) mesh.positions.push_back(to_float(v));
    mesh.indices.push_back({first, first + 1, first + 2});
    for (int r = 0; r < params.rays_per_triangle; ++r) {
      double a = rng.next_float(), b = rng.next_float();
      if (a + b > 1.0) {
        a = 1.0 - a;
        b = 1.0 - b;
      }
      const glm::dvec3 target = p[0] + a * (p[1] - p[0]) + b * (p[2] - p[0]);
      const double theta = params.degrees(rng) * std::numbers::pi / 180.0;
      const glm::dvec3 side = glm::normalize(glm::cross(n, glm::dvec3(sym(), sym(), sym())));
      const glm::dvec3 d = std::cos(theta) * side + (rng.next_below(2) ? 1.0 : -1.0) * std::sin(theta) * n;
      Ray ray;
      ray.org = to_float(target - (params.distance_min + params.distance_span * rng.next_float()) * d);
      ray.dir = to_float(params.direction_scale ? d * params.direction_scale(rng) : d);
      s.rays.push_back(ray);
    }
  }
  ensure_vertex_padding(mesh.positions);
  s.geometry.meshes.push_back(std::move(mesh));
  return s;
}

}  // namespace twinray::test
