#include "core/scene/procedural.h"

#include "core/sampling/rng.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

namespace twinray {

namespace {

// Embree reads vertex buffers with 16-byte loads: keep at least one spare vertex of capacity
// (SceneGeometry invariant).
void reserve_spare_vertex(TriangleMesh& mesh) { mesh.positions.reserve(mesh.positions.size() + 1); }

glm::vec3 uniform_in_cube(Rng& rng, float half_extent) {
  const float x = rng.next_float(), y = rng.next_float(), z = rng.next_float();
  return half_extent * (2.0f * glm::vec3(x, y, z) - 1.0f);
}

// Twice the triangle area relative to its longest edge squared: a scale-free measure of how thin it is.
float thinness(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2) {
  const float area2 = glm::length(glm::cross(p1 - p0, p2 - p0));
  const float e = std::max({glm::dot(p1 - p0, p1 - p0), glm::dot(p2 - p1, p2 - p1), glm::dot(p0 - p2, p0 - p2)});
  return e > 0.0f ? area2 / e : 0.0f;
}

TriangleMesh make_triangle_soup(std::size_t n, Rng& rng, std::uint32_t geom_id) {
  constexpr float kSpread = 0.15f;
  // Rejecting slivers keeps the soup free of (near-)degenerate triangles, which the loaders would drop.
  constexpr float kMinThinness = 0.01f;
  TriangleMesh mesh;
  mesh.geom_id = geom_id;
  mesh.positions.reserve(3 * n + 1);
  mesh.indices.reserve(n);
  while (mesh.indices.size() < n) {
    const glm::vec3 c = uniform_in_cube(rng, 1.0f - kSpread);
    const glm::vec3 p0 = c + uniform_in_cube(rng, kSpread);
    const glm::vec3 p1 = c + uniform_in_cube(rng, kSpread);
    const glm::vec3 p2 = c + uniform_in_cube(rng, kSpread);
    if (thinness(p0, p1, p2) < kMinThinness) continue;
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), {p0, p1, p2});
    mesh.indices.emplace_back(base, base + 1, base + 2);
  }
  reserve_spare_vertex(mesh);
  return mesh;
}

Sphere make_random_sphere(Rng& rng, std::uint32_t geom_id) {
  Sphere s;
  s.geom_id = geom_id;
  s.center = uniform_in_cube(rng, 1.0f);
  s.radius = 0.02f + 0.1f * rng.next_float();
  return s;
}

TriangleMesh make_icosphere(const glm::vec3& center, float radius, int subdivisions, std::uint32_t geom_id) {
  // Unit-sphere directions are refined in double and rounded once at the end, so a shared vertex gets one
  // position no matter which face created it (it is created only once anyway: see `midpoint`).
  using DVec = std::array<double, 3>;
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<DVec> dirs = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                            {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  // Counter-clockwise seen from outside.
  std::vector<std::array<std::uint32_t, 3>> faces = {
      {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  const auto normalized = [](const DVec& v) {
    const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return DVec{v[0] / len, v[1] / len, v[2] / len};
  };
  for (DVec& d : dirs) d = normalized(d);

  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
    const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      const DVec& pa = dirs[a];
      const DVec& pb = dirs[b];
      dirs.push_back(normalized({pa[0] + pb[0], pa[1] + pb[1], pa[2] + pb[2]}));
      const auto id = static_cast<std::uint32_t>(dirs.size() - 1);
      midpoints.emplace(key, id);
      return id;
    };
    std::vector<std::array<std::uint32_t, 3>> refined;
    refined.reserve(4 * faces.size());
    for (const auto& f : faces) {
      const std::uint32_t ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      refined.push_back({f[0], ab, ca});
      refined.push_back({f[1], bc, ab});
      refined.push_back({f[2], ca, bc});
      refined.push_back({ab, bc, ca});
    }
    faces = std::move(refined);
  }

  TriangleMesh mesh;
  mesh.geom_id = geom_id;
  mesh.positions.reserve(dirs.size() + 1);
  for (const DVec& d : dirs)
    mesh.positions.emplace_back(static_cast<float>(center.x + radius * d[0]),
                                static_cast<float>(center.y + radius * d[1]),
                                static_cast<float>(center.z + radius * d[2]));
  mesh.indices.reserve(faces.size());
  for (const auto& f : faces) mesh.indices.emplace_back(f[0], f[1], f[2]);
  return mesh;
}

}  // namespace

SceneGeometry tessellated_sphere(const glm::vec3& center, float radius, int subdivisions) {
  SceneGeometry g;
  g.meshes.push_back(make_icosphere(center, radius, subdivisions, 0));
  return g;
}

SceneGeometry random_triangle_soup(std::size_t n, std::uint64_t seed) {
  Rng rng(seed, 1);
  SceneGeometry g;
  g.meshes.push_back(make_triangle_soup(n, rng, 0));
  return g;
}

SceneGeometry sliver_soup(std::size_t n, std::uint64_t seed) {
  Rng rng(seed, 6);
  SceneGeometry g;
  g.meshes.push_back(make_triangle_soup(n, rng, 0));
  TriangleMesh& mesh = g.meshes.front();
  // Every fourth triangle, from index 1 on, becomes a sliver along its first edge: its apex moved to a point
  // of that edge, lifted off it by the edge's length over the aspect. Index 1 has the largest aspect, so
  // the triangles after it are numbered after a sliver that any area threshold of a "degenerate" test drops.
  for (std::size_t i = 1; i < mesh.indices.size(); i += 4) {
    const glm::uvec3 tri = mesh.indices[i];
    const glm::dvec3 p0(mesh.positions[tri.x]), p1(mesh.positions[tri.y]), p2(mesh.positions[tri.z]);
    const glm::dvec3 edge = p1 - p0;
    const glm::dvec3 normal_in_plane = glm::cross(glm::cross(edge, p2 - p0), edge);
    if (!(glm::dot(normal_in_plane, normal_in_plane) > 0.0)) continue;  // a degenerate soup triangle stays as it is
    const glm::dvec3 lift = glm::normalize(normal_in_plane);
    double aspect = i == 1 ? 1e7 : std::pow(10.0, 3.0 + 4.0 * rng.next_double());
    // Rounded to float the apex must stay off the edge (the loaders drop collinear triangles). A draw that
    // rounds onto it is redrawn at a new point of the edge, and every 8 draws the lift doubles. After 64
    // draws (never reached by the suites' scenes) the triangle stays as it was, so the loop always ends.
    for (int draw = 0;; ++draw) {
      if (draw > 0 && draw % 8 == 0) aspect /= 2.0;
      const double s = 0.1 + 0.8 * rng.next_double();
      const glm::vec3 apex(p0 + s * edge + (glm::length(edge) / aspect) * lift);
      const glm::dvec3 area2 = glm::cross(edge, glm::dvec3(apex) - p0);
      const bool off_edge = glm::dot(area2, area2) > 0.0;
      if (off_edge) mesh.positions[tri.z] = apex;
      if (off_edge || draw == 63) break;
    }
  }
  return g;
}

SceneGeometry coincident_boxes(std::size_t n, int per_cluster, std::uint64_t seed) {
  // The triples of cube corners (bit a of a corner: + in axis a) that take both signs in every axis.
  std::vector<std::array<int, 3>> triples;
  for (int i = 0; i < 8; ++i)
    for (int j = i + 1; j < 8; ++j)
      for (int k = j + 1; k < 8; ++k)
        if ((i & j & k) == 0 && (i | j | k) == 7) triples.push_back({i, j, k});
  per_cluster = std::clamp(per_cluster, 1, static_cast<int>(triples.size()));
  Rng rng(seed, 5);
  TriangleMesh mesh;
  mesh.geom_id = 0;
  for (std::size_t c = 0; c < n; ++c) {
    const auto grid = [&rng] { return static_cast<float>(static_cast<int>(rng.next_below(113)) - 56) * 0x1p-6f; };
    const glm::vec3 centre(grid(), grid(), grid());
    const float r = static_cast<float>(2 + rng.next_below(6)) * 0x1p-6f;
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    for (int corner = 0; corner < 8; ++corner)
      mesh.positions.push_back(centre + r * glm::vec3((corner & 1) ? 1.0f : -1.0f, (corner & 2) ? 1.0f : -1.0f,
                                                      (corner & 4) ? 1.0f : -1.0f));
    // A different choice of triples per cluster: start at a random one and step by a prime.
    const std::uint32_t start = rng.next_below(static_cast<std::uint32_t>(triples.size()));
    for (int b = 0; b < per_cluster; ++b) {
      const std::array<int, 3>& t = triples[(start + 7u * static_cast<std::uint32_t>(b)) % triples.size()];
      mesh.indices.emplace_back(base + static_cast<std::uint32_t>(t[0]), base + static_cast<std::uint32_t>(t[1]),
                                base + static_cast<std::uint32_t>(t[2]));
    }
  }
  mesh.positions.reserve(mesh.positions.size() + 1);
  SceneGeometry g;
  g.meshes.push_back(std::move(mesh));
  return g;
}

SceneGeometry nested_levels(int levels, std::uint64_t seed, std::optional<glm::vec3> cone, bool cap) {
  levels = std::clamp(levels, 1, kMaxNestLevels);
  constexpr float kTunnelRadians = 0.1f;
  constexpr int kBlocked = 3;
  // 2^(36 - 1.5 j) as 2^0 or 2^(1/2) = 2 * 2^(-1/2) times a power of two: exact steps, no rounding drift.
  constexpr std::array<float, 2> kHalves = {1.0f, 0.70710677f};
  std::vector<std::size_t> counts(static_cast<std::size_t>(levels));
  double count = 1.0;
  for (std::size_t j = counts.size(); j-- > 0;) {
    counts[j] = static_cast<std::size_t>(std::ceil(count));
    count *= 1.15;
  }
  Rng rng(seed, 4);
  TriangleMesh mesh;
  mesh.geom_id = 0;
  // Two cones, around (1, 1, 1) and around (-1, 1, 1). Not the opposite of the first: on a line through the
  // origin a binned builder's split near 0 takes inner levels of one cone with the other, and the chain
  // is lost (measured: 22 pending entries at most instead of 49). Or the one cone asked for.
  const std::vector<glm::vec3> cones =
      cone ? std::vector<glm::vec3>{*cone} : std::vector<glm::vec3>{{1.0f, 1.0f, 1.0f}, {-1.0f, 1.0f, 1.0f}};
  const auto add = [&mesh](const std::array<glm::vec3, 3>& v) {
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), v.begin(), v.end());
    mesh.indices.emplace_back(base, base + 1, base + 2);
  };
  for (const glm::vec3& signs : cones) {
    // The tunnel: a cone of directions around the cone's axis that no level but the innermost kBlocked
    // crosses; those hold a small triangle across it. A ray along it passes every outer level's box without
    // a hit, so its only hits are among the last entries pushed, for any-hit queries too (elsewhere the many
    // triangles of the outer levels give every ray an early hit).
    const glm::vec3 axis = glm::normalize(signs);
    const float tunnel_cos = std::cos(kTunnelRadians);
    const auto crosses_tunnel = [&](const std::array<glm::vec3, 3>& v) {
      constexpr int kSteps = 16;  // points of the triangle every 1/16 of its edges
      for (int i = 0; i <= kSteps; ++i)
        for (int k = 0; i + k <= kSteps; ++k) {
          const float a = static_cast<float>(i) / kSteps, b = static_cast<float>(k) / kSteps;
          const glm::vec3 p = (1.0f - a - b) * v[0] + a * v[1] + b * v[2];
          if (glm::dot(glm::normalize(p), axis) > tunnel_cos) return true;
        }
      return false;
    };
    for (int j = 0; j < levels; ++j) {
      const float scale = std::ldexp(kHalves[static_cast<std::size_t>(j % 2)], 36 - 3 * (j / 2) - j % 2);
      const bool blocked = j >= levels - kBlocked;
      for (std::size_t k = 0; k < counts[static_cast<std::size_t>(j)]; ++k) {
        std::array<glm::vec3, 3> v, unit;
        do {
          const float distance = scale * (0.7f + 0.3f * rng.next_float());
          for (glm::vec3& p : v) {
            const float along = distance * (0.9f + 0.2f * rng.next_float());
            for (int a = 0; a < 3; ++a) p[a] = along * (0.6f + 0.8f * rng.next_float());
            p *= signs;
          }
          for (int m = 0; m < 3; ++m) unit[static_cast<std::size_t>(m)] = v[static_cast<std::size_t>(m)] / scale;
        } while (glm::length(glm::cross(unit[1] - unit[0], unit[2] - unit[0])) < 1e-3f ||
                 ((!blocked || cap) && crosses_tunnel(unit)));  // capped: only the small ones cross it
        add(v);
      }
      if (blocked) {
        // Across the tunnel, centred on its axis, half its radius wide.
        const glm::vec3 u = glm::normalize(glm::cross(axis, glm::vec3(0.0f, 0.0f, 1.0f))), w = glm::cross(axis, u);
        const float distance = 0.85f * scale, radius = distance * std::tan(0.5f * kTunnelRadians);
        std::array<glm::vec3, 3> v;
        for (int m = 0; m < 3; ++m) {
          const float angle = 2.0943951f * static_cast<float>(m);
          v[static_cast<std::size_t>(m)] = distance * axis + radius * (std::cos(angle) * u + std::sin(angle) * w);
        }
        add(v);
      }
    }
  }
  if (cap) {
    // Beyond the outermost level (whose triangles lie within about 1.6 * 2^36 of the origin), a triangle
    // whose inscribed circle is the tunnel's cross-section: every ray along the tunnel that passes the
    // innermost levels' triangles hits it.
    for (const glm::vec3& signs : cones) {
      const glm::vec3 axis = glm::normalize(signs);
      const glm::vec3 u = glm::normalize(glm::cross(axis, glm::vec3(0.0f, 0.0f, 1.0f))), w = glm::cross(axis, u);
      const float distance = std::ldexp(1.0f, 38), radius = 2.0f * distance * std::tan(kTunnelRadians);
      std::array<glm::vec3, 3> v;
      for (int m = 0; m < 3; ++m) {
        const float angle = 2.0943951f * static_cast<float>(m);
        v[static_cast<std::size_t>(m)] = distance * axis + radius * (std::cos(angle) * u + std::sin(angle) * w);
      }
      add(v);
    }
  }
  mesh.positions.reserve(mesh.positions.size() + 1);
  SceneGeometry g;
  g.meshes.push_back(std::move(mesh));
  return g;
}

SceneGeometry grid_mesh(int nx, int ny) {
  TriangleMesh mesh;
  mesh.geom_id = 0;
  const auto vertex = [nx](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
  mesh.positions.reserve(static_cast<std::size_t>((nx + 1) * (ny + 1) + 1));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) mesh.positions.emplace_back(static_cast<float>(i), static_cast<float>(j), 0.0f);
  mesh.indices.reserve(static_cast<std::size_t>(2 * nx * ny));
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const std::uint32_t v00 = vertex(i, j), v10 = vertex(i + 1, j), v01 = vertex(i, j + 1),
                          v11 = vertex(i + 1, j + 1);
      if ((i + j) % 2 == 0) {  // diagonal v00-v11
        mesh.indices.emplace_back(v00, v10, v11);
        mesh.indices.emplace_back(v00, v11, v01);
      } else {  // diagonal v10-v01
        mesh.indices.emplace_back(v00, v10, v01);
        mesh.indices.emplace_back(v10, v11, v01);
      }
    }
  }
  SceneGeometry g;
  g.meshes.push_back(std::move(mesh));
  return g;
}

SceneGeometry random_spheres(std::size_t n, std::uint64_t seed) {
  Rng rng(seed, 2);
  SceneGeometry g;
  g.spheres.reserve(n);
  for (std::size_t k = 0; k < n; ++k) g.spheres.push_back(make_random_sphere(rng, static_cast<std::uint32_t>(k)));
  return g;
}

SceneGeometry mixed_spheres_and_triangles(std::size_t n_spheres, std::size_t n_triangles, std::uint64_t seed) {
  Rng rng(seed, 3);
  SceneGeometry g;
  g.meshes.push_back(make_triangle_soup(n_triangles, rng, 0));
  for (std::size_t k = 0; k < n_spheres; ++k)
    g.spheres.push_back(make_random_sphere(rng, static_cast<std::uint32_t>(k + 1)));
  g.meshes.push_back(make_icosphere(glm::vec3(0.0f), 0.5f, 3, static_cast<std::uint32_t>(n_spheres + 1)));
  return g;
}

}  // namespace twinray
