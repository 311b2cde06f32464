#include "core/scene/procedural_bench.h"

#include "core/sampling/rng.h"
#include "core/scene/mesh_scene.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace twinray {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// Random triangles thinner than this (twice the area over the longest edge squared) are redrawn: the
// loaders would drop (near-)degenerate ones, and the benchmark should measure what a renderer would keep.
// 1e-4 still leaves the hairball's thinnest needles (about 1 : 2400 at 4M triangles) a width of hundreds of
// float ulps at unit coordinates, far from degenerate.
constexpr float kMinThinness = 1e-4f;

float thinness(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2) {
  const float area2 = glm::length(glm::cross(p1 - p0, p2 - p0));
  const float e = std::max({glm::dot(p1 - p0, p1 - p0), glm::dot(p2 - p1, p2 - p1), glm::dot(p0 - p2, p0 - p2)});
  return e > 0.0f ? area2 / e : 0.0f;
}

glm::vec3 uniform_in_cube(Rng& rng) {
  return 2.0f * glm::vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 1.0f;
}

glm::vec3 uniform_direction(Rng& rng) {
  const float z = 1.0f - 2.0f * rng.next_float();
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  const float phi = 2.0f * kPi * rng.next_float();
  return {r * std::cos(phi), r * std::sin(phi), z};
}

SceneGeometry single_mesh(TriangleMesh mesh) {
  mesh.geom_id = 0;
  // Embree reads vertex buffers with 16-byte loads: one spare vertex of capacity (SceneGeometry invariant).
  mesh.positions.reserve(mesh.positions.size() + 1);
  SceneGeometry g;
  g.meshes.push_back(std::move(mesh));
  return g;
}

std::uint32_t u32(std::size_t i) { return static_cast<std::uint32_t>(i); }

// Independent random triangles (three fresh vertices each): vertices = center + spread * random offsets.
SceneGeometry random_triangles(std::size_t n, Rng& rng, auto&& make_triangle) {
  TriangleMesh mesh;
  mesh.positions.reserve(3 * n + 1);
  mesh.indices.reserve(n);
  while (mesh.indices.size() < n) {
    glm::vec3 p[3];
    make_triangle(rng, p);
    if (!(thinness(p[0], p[1], p[2]) >= kMinThinness)) continue;
    const std::uint32_t base = u32(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), {p[0], p[1], p[2]});
    mesh.indices.emplace_back(base, base + 1, base + 2);
  }
  return single_mesh(std::move(mesh));
}

}  // namespace

std::string_view to_string(BenchFamily family) {
  switch (family) {
    case BenchFamily::Sphere: return "sphere";
    case BenchFamily::Soup: return "soup";
    case BenchFamily::Terrain: return "terrain";
    case BenchFamily::Hairball: return "hairball";
  }
  return "?";
}

std::optional<BenchFamily> parse_bench_family(std::string_view name) {
  for (BenchFamily f : kAllBenchFamilies)
    if (to_string(f) == name) return f;
  return std::nullopt;
}

SceneGeometry bench_sphere(std::size_t triangles) {
  // Latitude-longitude tessellation with `segments` = 2 * `rings`: 2 * segments * (rings - 1) triangles
  // (one fan row at each pole, two per quad elsewhere), about 4 rings^2.
  const int rings = std::max(4, static_cast<int>(std::lround(std::sqrt(static_cast<double>(triangles) / 4.0))));
  const int segments = 2 * rings;
  TriangleMesh mesh;
  mesh.positions.push_back({0.0f, 1.0f, 0.0f});  // north pole
  for (int r = 1; r < rings; ++r) {
    const float theta = kPi * static_cast<float>(r) / static_cast<float>(rings);
    for (int s = 0; s < segments; ++s) {
      const float phi = 2.0f * kPi * static_cast<float>(s) / static_cast<float>(segments);
      mesh.positions.push_back({std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi)});
    }
  }
  mesh.positions.push_back({0.0f, -1.0f, 0.0f});  // south pole
  const std::uint32_t south = u32(mesh.positions.size() - 1);
  auto ring_vertex = [&](int r, int s) { return u32(1 + static_cast<std::size_t>(r - 1) * segments + (s % segments)); };
  // Counter-clockwise seen from outside: phi grows toward -z, i.e. counter-clockwise seen from +y.
  for (int s = 0; s < segments; ++s) mesh.indices.emplace_back(0u, ring_vertex(1, s), ring_vertex(1, s + 1));
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const std::uint32_t a = ring_vertex(r, s), b = ring_vertex(r, s + 1);
      const std::uint32_t c = ring_vertex(r + 1, s), d = ring_vertex(r + 1, s + 1);
      mesh.indices.emplace_back(a, c, d);
      mesh.indices.emplace_back(a, d, b);
    }
  for (int s = 0; s < segments; ++s) mesh.indices.emplace_back(south, ring_vertex(rings - 1, s + 1), ring_vertex(rings - 1, s));
  return single_mesh(std::move(mesh));
}

SceneGeometry bench_soup(std::size_t triangles, std::uint64_t seed) {
  // Vertices within `spread` of a random center in [-1,1]^3. The spread falls as N^(-1/2), so the total
  // triangle area, and with it the number of triangles a ray crosses, stays about constant across the
  // series (a fixed spread would make a 4M soup an opaque block costing thousands of tests per ray).
  const std::size_t n = std::max<std::size_t>(triangles, 1);
  const float spread = 0.25f * std::sqrt(1024.0f / static_cast<float>(n));
  Rng rng(seed, 0x50u);
  return random_triangles(n, rng, [spread](Rng& r, glm::vec3* p) {
    const glm::vec3 c = uniform_in_cube(r) * (1.0f - spread);
    for (int k = 0; k < 3; ++k) p[k] = c + spread * uniform_in_cube(r);
  });
}

SceneGeometry bench_terrain(std::size_t triangles, std::uint64_t seed) {
  // A grid of cells x cells squares over [-1,1]^2 in the xz plane, height y from a few octaves of
  // randomly phased sine waves (smooth, deterministic, no noise tables).
  const int cells = std::max(2, static_cast<int>(std::lround(std::sqrt(static_cast<double>(triangles) / 2.0))));
  Rng rng(seed, 0x7e77u);
  constexpr int kOctaves = 6;
  float phase[kOctaves][2], angle[kOctaves];
  for (int o = 0; o < kOctaves; ++o) {
    phase[o][0] = 2.0f * kPi * rng.next_float();
    phase[o][1] = 2.0f * kPi * rng.next_float();
    angle[o] = 2.0f * kPi * rng.next_float();
  }
  auto height = [&](float x, float z) {
    float h = 0.0f, amplitude = 0.12f, frequency = 1.5f;
    for (int o = 0; o < kOctaves; ++o) {
      const float u = std::cos(angle[o]) * x - std::sin(angle[o]) * z;
      const float v = std::sin(angle[o]) * x + std::cos(angle[o]) * z;
      h += amplitude * std::sin(frequency * u + phase[o][0]) * std::sin(frequency * v + phase[o][1]);
      amplitude *= 0.5f;
      frequency *= 2.1f;
    }
    return h;
  };
  TriangleMesh mesh;
  const std::size_t side = static_cast<std::size_t>(cells) + 1;
  mesh.positions.reserve(side * side + 1);
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i) {
      const float x = -1.0f + 2.0f * static_cast<float>(i) / static_cast<float>(cells);
      const float z = -1.0f + 2.0f * static_cast<float>(j) / static_cast<float>(cells);
      mesh.positions.push_back({x, height(x, z), z});
    }
  mesh.indices.reserve(2 * static_cast<std::size_t>(cells) * static_cast<std::size_t>(cells));
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      const std::uint32_t a = u32(static_cast<std::size_t>(j) * side + static_cast<std::size_t>(i));
      const std::uint32_t b = a + 1, c = a + u32(side), d = c + 1;
      // Counter-clockwise seen from +y (z grows toward the viewer): (a, c, b) and (b, c, d).
      mesh.indices.emplace_back(a, c, b);
      mesh.indices.emplace_back(b, c, d);
    }
  return single_mesh(std::move(mesh));
}

SceneGeometry bench_hairball(std::size_t triangles, std::uint64_t seed) {
  // Needles with random centers in the unit ball and random directions. At 1k triangles they are 0.6 long
  // and 0.004 wide (150 : 1); with more triangles the length shrinks as N^(-1/3) (a needle stays about ten
  // times the mean spacing of the centers, so boxes keep overlapping at every level of the tree) and the
  // width as N^(-2/3), which keeps the total area, and so the number of needles a ray crosses, constant.
  // Without that, a 1M-triangle ball is so dense that one shadow ray tests thousands of triangles.
  const std::size_t n = std::max<std::size_t>(triangles, 1);
  const float shrink = std::cbrt(1024.0f / static_cast<float>(n));
  const float length = 0.6f * shrink, width = 0.004f * shrink * shrink;
  Rng rng(seed, 0x4a1bu);
  return random_triangles(n, rng, [length, width](Rng& r, glm::vec3* p) {
    glm::vec3 c;
    do c = uniform_in_cube(r);
    while (glm::dot(c, c) > 1.0f);
    const glm::vec3 d = uniform_direction(r);
    glm::vec3 side = glm::cross(d, uniform_direction(r));
    const float len = glm::length(side);
    side = len > 0.1f ? side / len : glm::normalize(glm::cross(d, std::abs(d.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0)));
    p[0] = c - 0.5f * length * d;
    p[1] = c + 0.5f * length * d;
    p[2] = c + width * side;
  });
}

SceneGeometry bench_geometry(BenchFamily family, std::size_t triangles, std::uint64_t seed) {
  switch (family) {
    case BenchFamily::Sphere: return bench_sphere(triangles);
    case BenchFamily::Soup: return bench_soup(triangles, seed);
    case BenchFamily::Terrain: return bench_terrain(triangles, seed);
    case BenchFamily::Hairball: return bench_hairball(triangles, seed);
  }
  return {};
}

Scene bench_scene(SceneGeometry geometry, const std::string& name, int width, int height) {
  Scene scene;
  scene.source = name;
  scene.camera = framing_camera(geometry.bounds(), width, height, 40.0f);
  Material white;
  white.name = "white";
  white.type = MaterialType::Diffuse;
  white.albedo = glm::vec3(0.8f);
  scene.materials.push_back(white);
  for (std::uint32_t id = 0; id < geometry.geom_id_end(); ++id) {
    ShapeInfo shape;
    shape.name = name;
    shape.kind = ShapeKind::Mesh;
    for (const Sphere& s : geometry.spheres)
      if (s.geom_id == id) shape.kind = ShapeKind::Sphere;
    scene.shapes.push_back(shape);
  }
  scene.geometry = std::move(geometry);
  return scene;
}

}  // namespace twinray
