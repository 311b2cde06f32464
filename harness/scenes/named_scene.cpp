#include "harness/scenes/named_scene.h"

#include "core/scene/mesh_scene.h"
#include "core/scene/procedural.h"
#include "core/scene/scene_loader.h"
#include "core/scene/shared_data.h"
#include "core/util/input_error.h"
#include "harness/stress/stress_support.h"

#include <fmt/core.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <limits>
#include <utility>

namespace twinray {

namespace {

// Generous caps: a procedural name comes from a command line or a suite, and a typo must not allocate
// hundreds of gigabytes.
constexpr long long kMaxProceduralTriangles = 20'000'000;
constexpr int kMaxSphereSubdivisions = 9;  // 20 * 4^9 = 5.2M triangles

class ProceduralArgs {
 public:
  ProceduralArgs(std::string_view full_name, std::string_view kind, std::vector<std::string> args)
      : full_name_(full_name), kind_(kind), args_(std::move(args)) {}

  std::size_t size() const { return args_.size(); }

  void expect_count(std::size_t lo, std::size_t hi, std::string_view usage) const {
    if (args_.size() < lo || args_.size() > hi)
      fail(fmt::format("'{}' takes {} (procedural:{}:{})", kind_, lo == hi && lo == 0 ? "no arguments" : "arguments",
                       kind_, usage));
  }

  long long integer(std::size_t i, long long lo, long long hi, std::string_view what) const {
    const std::string& s = args_[i];
    long long value = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    if (ec != std::errc() || end != s.data() + s.size() || value < lo || value > hi)
      fail(fmt::format("{} must be an integer in [{}, {}], got '{}'", what, lo, hi, s));
    return value;
  }

  float real(std::size_t i, std::string_view what, bool positive = false) const {
    const std::string& s = args_[i];
    char* end = nullptr;
    const float value = std::strtof(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(value) || (positive && !(value > 0.0f)))
      fail(fmt::format("{} must be a finite{} number, got '{}'", what, positive ? " positive" : "", s));
    return value;
  }

  [[noreturn]] void fail(const std::string& message) const { throw InputError(full_name_, "", message); }

 private:
  std::string full_name_;
  std::string kind_;
  std::vector<std::string> args_;
};

SceneGeometry one_triangle() {
  SceneGeometry g;
  TriangleMesh m;
  m.positions = {{0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}};
  m.positions.reserve(4);
  m.indices = {{0u, 1u, 2u}};
  g.meshes.push_back(std::move(m));
  return g;
}

// n copies of one triangle, each with its own three (equal) vertices: every centroid and box coincide, the
// case where a SAH builder finds no split that separates anything.
SceneGeometry identical_triangles(std::size_t n) {
  SceneGeometry g;
  TriangleMesh m;
  m.positions.reserve(3 * n + 1);
  m.indices.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const auto base = static_cast<std::uint32_t>(m.positions.size());
    m.positions.insert(m.positions.end(), {{-0.5f, -0.25f, 0.0f}, {0.5f, -0.25f, 0.0f}, {0.0f, 0.5f, 0.0f}});
    m.indices.emplace_back(base, base + 1, base + 2);
  }
  g.meshes.push_back(std::move(m));
  return g;
}

// Exact duplicates, the one kind of tie every correct float intersector reports with bit-identical t: mesh
// 0 lists each soup triangle twice (prim k and prim n + k, same vertex indices), mesh 1 is a copy of mesh 0.
// Under the tie rule (hit.h) the answer is always geom 0, the lower prim.
SceneGeometry duplicated_soup(std::size_t n, std::uint64_t seed) {
  SceneGeometry g = random_triangle_soup(n, seed);
  TriangleMesh& m = g.meshes[0];
  const std::size_t count = m.indices.size();
  for (std::size_t k = 0; k < count; ++k) m.indices.push_back(m.indices[k]);
  TriangleMesh copy = m;
  copy.geom_id = 1;
  copy.positions.reserve(copy.positions.size() + 1);
  g.meshes.push_back(std::move(copy));
  return g;
}

// duplicated_soup with mesh 1's triangles listed in reverse order: mesh 0's triangle k (and n + k) is mesh 1's
// 2n - 1 - k and n - 1 - k, so for k >= n / 2 mesh 1's copy has the lower prim_id. The tie rule compares
// geom_id first and still names geom 0, prim k; a plugin that compares prim_id first names mesh 1's copy.
SceneGeometry reversed_duplicated_soup(std::size_t n, std::uint64_t seed) {
  SceneGeometry g = duplicated_soup(n, seed);
  std::reverse(g.meshes[1].indices.begin(), g.meshes[1].indices.end());
  return g;
}

// Spheres at the scales where a sphere test loses its digits: tiny (radius 1e-3), ordinary, huge (radius
// 1e4, its surface passing near the others), and far from the origin (1e4 away).
SceneGeometry sphere_sizes() {
  SceneGeometry g;
  const struct {
    glm::vec3 center;
    float radius;
  } spheres[] = {{{0.0f, 0.0f, 0.0f}, 1.0f},
                 {{2.5f, 0.0f, 0.0f}, 1e-3f},
                 {{0.0f, -10001.5f, 0.0f}, 1e4f},
                 {{1e4f, 0.0f, 0.0f}, 1.0f},
                 {{-2.5f, 0.5f, 0.0f}, 0.75f}};
  std::uint32_t id = 0;
  for (const auto& s : spheres) g.spheres.push_back({id++, s.center, s.radius});
  return g;
}

SceneGeometry box_mesh(int lo, int hi) {
  SceneGeometry g;
  g.meshes.push_back(stress::integer_box_mesh(lo, hi, 0));
  g.meshes.back().positions.reserve(g.meshes.back().positions.size() + 1);
  return g;
}

// The closed box [lo, hi]^3 of box_mesh with every triangle listed `copies` times in its one mesh, the copies
// in a seeded random order (Fisher-Yates on splitmix64, the same on every platform). Each triangle is a cluster
// of identical, flat, axis-aligned boxes that no split separates: a builder whose leaves hold fewer than
// `copies` primitives keeps the cluster in several leaves whose boxes are entered at exactly the same t, and the
// tie rule names the copy with the lowest prim_id, in whichever leaf it is. A traversal that prunes a node whose
// entry (computed in double) lies beyond the hit's t rounded to float skips the later leaves half the time.
SceneGeometry duplicated_box(int lo, int hi, int copies, std::uint64_t seed) {
  SceneGeometry g = box_mesh(lo, hi);
  TriangleMesh& m = g.meshes[0];
  std::vector<glm::uvec3> listed;
  listed.reserve(m.indices.size() * static_cast<std::size_t>(copies));
  for (const glm::uvec3& t : m.indices)
    for (int c = 0; c < copies; ++c) listed.push_back(t);
  std::uint64_t state = seed;
  const auto next = [&state] {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  };
  for (std::size_t i = listed.size(); i > 1; --i) std::swap(listed[i - 1], listed[next() % i]);
  m.indices = std::move(listed);
  return g;
}

struct Generator {
  ProceduralKind kind;
  std::function<SceneGeometry(const ProceduralArgs&)> make;
};

const std::vector<Generator>& generators() {
  static const std::vector<Generator> list = {
      {{"empty", "", "no geometry at all"},
       [](const ProceduralArgs& a) {
         a.expect_count(0, 0, "");
         return SceneGeometry{};
       }},
      {{"triangle", "", "one triangle (0,0,0) (1,0,0) (0,1,0)"},
       [](const ProceduralArgs& a) {
         a.expect_count(0, 0, "");
         return one_triangle();
       }},
      {{"identical-triangles", "N", "N copies of one triangle (every box and centroid coincide)"},
       [](const ProceduralArgs& a) {
         a.expect_count(1, 1, "N");
         return identical_triangles(static_cast<std::size_t>(a.integer(0, 1, kMaxProceduralTriangles, "N")));
       }},
      {{"grid", "NX:NY", "a planar grid of NX x NY unit squares in z = 0, two triangles each"},
       [](const ProceduralArgs& a) {
         a.expect_count(2, 2, "NX:NY");
         const long long nx = a.integer(0, 1, 4096, "NX"), ny = a.integer(1, 1, 4096, "NY");
         return grid_mesh(static_cast<int>(nx), static_cast<int>(ny));
       }},
      {{"soup", "N:SEED", "N random, overlapping triangles in [-1, 1]^3"},
       [](const ProceduralArgs& a) {
         a.expect_count(2, 2, "N:SEED");
         return random_triangle_soup(static_cast<std::size_t>(a.integer(0, 1, kMaxProceduralTriangles, "N")),
                                     static_cast<std::uint64_t>(a.integer(1, 0, std::numeric_limits<long long>::max(), "SEED")));
       }},
      {{"sliver-soup", "N:SEED",
        "a soup of N triangles in [-1, 1]^3, every fourth (from index 1) a thin valid sliver of aspect 1e3 to 1e7"},
       [](const ProceduralArgs& a) {
         a.expect_count(2, 2, "N:SEED");
         return sliver_soup(static_cast<std::size_t>(a.integer(0, 1, kMaxProceduralTriangles, "N")),
                            static_cast<std::uint64_t>(a.integer(1, 0, std::numeric_limits<long long>::max(), "SEED")));
       }},
      {{"duplicates", "N:SEED", "a soup of N triangles listed twice in mesh 0, and mesh 1 a copy of mesh 0 (exact ties)"},
       [](const ProceduralArgs& a) {
         a.expect_count(2, 2, "N:SEED");
         return duplicated_soup(static_cast<std::size_t>(a.integer(0, 1, kMaxProceduralTriangles / 4, "N")),
                                static_cast<std::uint64_t>(a.integer(1, 0, std::numeric_limits<long long>::max(), "SEED")));
       }},
      {{"duplicates-reversed", "N:SEED",
        "duplicates with mesh 1's triangles listed in reverse order (a later geometry's copy has the lower prim_id)"},
       [](const ProceduralArgs& a) {
         a.expect_count(2, 2, "N:SEED");
         return reversed_duplicated_soup(
             static_cast<std::size_t>(a.integer(0, 1, kMaxProceduralTriangles / 4, "N")),
             static_cast<std::uint64_t>(a.integer(1, 0, std::numeric_limits<long long>::max(), "SEED")));
       }},
      {{"sphere-mesh", "SUBDIVISIONS[:CX:CY:CZ:RADIUS]",
        "a closed, watertight tessellated sphere of 20 * 4^SUBDIVISIONS triangles (default centre 0, radius 1)"},
       [](const ProceduralArgs& a) {
         if (a.size() != 1 && a.size() != 5) a.expect_count(1, 1, "SUBDIVISIONS[:CX:CY:CZ:RADIUS]");
         const int s = static_cast<int>(a.integer(0, 0, kMaxSphereSubdivisions, "SUBDIVISIONS"));
         glm::vec3 c(0.0f);
         float r = 1.0f;
         if (a.size() == 5) {
           c = {a.real(1, "CX"), a.real(2, "CY"), a.real(3, "CZ")};
           r = a.real(4, "RADIUS", true);
         }
         return tessellated_sphere(c, r, s);
       }},
      {{"duplicates-box", "LO:HI:COPIES:SEED",
        "the box [LO, HI]^3 with every triangle listed COPIES times in one mesh, in a seeded random order (exact "
        "ties among flat, axis-aligned triangles)"},
       [](const ProceduralArgs& a) {
         a.expect_count(4, 4, "LO:HI:COPIES:SEED");
         const long long lo = a.integer(0, -64, 63, "LO"), hi = a.integer(1, lo + 1, 64, "HI");
         return duplicated_box(static_cast<int>(lo), static_cast<int>(hi),
                               static_cast<int>(a.integer(2, 1, 64, "COPIES")),
                               static_cast<std::uint64_t>(a.integer(3, 0, std::numeric_limits<long long>::max(), "SEED")));
       }},
      {{"box", "LO:HI", "the closed, axis-aligned box [LO, HI]^3, each face split into unit squares"},
       [](const ProceduralArgs& a) {
         a.expect_count(2, 2, "LO:HI");
         const long long lo = a.integer(0, -512, 511, "LO"), hi = a.integer(1, lo + 1, 512, "HI");
         return box_mesh(static_cast<int>(lo), static_cast<int>(hi));
       }},
      {{"spheres", "N:SEED", "N random spheres in [-1, 1]^3, radii 0.02 to 0.12"},
       [](const ProceduralArgs& a) {
         a.expect_count(2, 2, "N:SEED");
         return random_spheres(static_cast<std::size_t>(a.integer(0, 1, 1'000'000, "N")),
                               static_cast<std::uint64_t>(a.integer(1, 0, std::numeric_limits<long long>::max(), "SEED")));
       }},
      {{"sphere-sizes", "", "spheres of radius 1e-3, 0.75, 1 and 1e4, and one 1e4 away from the origin"},
       [](const ProceduralArgs& a) {
         a.expect_count(0, 0, "");
         return sphere_sizes();
       }},
      {{"coincident-boxes", "N:PER_CLUSTER:SEED",
        "N clusters of PER_CLUSTER different triangles whose bounding boxes are one and the same cube"},
       [](const ProceduralArgs& a) {
         a.expect_count(3, 3, "N:PER_CLUSTER:SEED");
         return coincident_boxes(static_cast<std::size_t>(a.integer(0, 1, kMaxProceduralTriangles / 32, "N")),
                                 static_cast<int>(a.integer(1, 1, 32, "PER_CLUSTER")),
                                 static_cast<std::uint64_t>(a.integer(2, 0, std::numeric_limits<long long>::max(), "SEED")));
       }},
      {{"nest", "LEVELS:SEED[:SX:SY:SZ[:CAP]]",
        "nested levels of triangles shrinking toward the origin (a deep tree along rays from the origin), in two "
        "cones or in the one around (SX, SY, SZ), each 1 or -1; CAP 1 adds a triangle across the cone's tunnel "
        "beyond the outermost level"},
       [](const ProceduralArgs& a) {
         if (a.size() != 2 && a.size() != 5 && a.size() != 6) a.expect_count(2, 2, "LEVELS:SEED[:SX:SY:SZ[:CAP]]");
         std::optional<glm::vec3> cone;
         if (a.size() >= 5) {
           glm::vec3 signs;
           for (int k = 0; k < 3; ++k) {
             const char* name = k == 0 ? "SX" : (k == 1 ? "SY" : "SZ");
             const long long sign = a.integer(static_cast<std::size_t>(2 + k), -1, 1, name);
             if (sign == 0) a.fail(fmt::format("{} must be 1 or -1, got 0", name));
             signs[k] = static_cast<float>(sign);
           }
           cone = signs;
         }
         const bool cap = a.size() == 6 && a.integer(5, 0, 1, "CAP") == 1;
         return nested_levels(static_cast<int>(a.integer(0, 1, kMaxNestLevels, "LEVELS")),
                              static_cast<std::uint64_t>(a.integer(1, 0, std::numeric_limits<long long>::max(), "SEED")),
                              cone, cap);
       }},
      {{"mixed", "NSPHERES:NTRIANGLES:SEED", "spheres and a triangle soup, ids interleaved, and a tessellated sphere"},
       [](const ProceduralArgs& a) {
         a.expect_count(3, 3, "NSPHERES:NTRIANGLES:SEED");
         return mixed_spheres_and_triangles(
             static_cast<std::size_t>(a.integer(0, 1, 1'000'000, "NSPHERES")),
             static_cast<std::size_t>(a.integer(1, 1, kMaxProceduralTriangles, "NTRIANGLES")),
             static_cast<std::uint64_t>(a.integer(2, 0, std::numeric_limits<long long>::max(), "SEED")));
       }},
  };
  return list;
}

std::vector<std::string> split(std::string_view text, char separator) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (;;) {
    const std::size_t at = text.find(separator, start);
    parts.emplace_back(text.substr(start, at == std::string_view::npos ? std::string_view::npos : at - start));
    if (at == std::string_view::npos) break;
    start = at + 1;
  }
  return parts;
}

// The default scene around generated geometry: one diffuse material, one shape per geometry id, no emitter,
// a camera that frames the geometry (as for a bare mesh file, core/scene/mesh_scene.h).
Scene wrap_geometry(SceneGeometry geometry, std::string_view name) {
  Scene scene;
  scene.source = std::string(name);
  scene.materials.push_back({"default", MaterialType::Diffuse, glm::vec3(0.8f), glm::vec3(1.0f), 1.5f, glm::vec3(0.0f)});
  scene.shapes.resize(geometry.geom_id_end());
  for (const TriangleMesh& m : geometry.meshes) scene.shapes[m.geom_id] = {fmt::format("mesh {}", m.geom_id), ShapeKind::Mesh, 0, {}};
  for (const Sphere& s : geometry.spheres) scene.shapes[s.geom_id] = {fmt::format("sphere {}", s.geom_id), ShapeKind::Sphere, 0, {}};
  scene.camera = framing_camera(geometry.bounds(), 256, 256, 40.0f);
  scene.environment.type = EnvironmentType::Constant;
  scene.environment.radiance = glm::vec3(1.0f);
  scene.geometry = std::move(geometry);
  return scene;
}

Scene load_procedural(std::string_view name) {
  const std::vector<std::string> parts = split(name.substr(kProceduralPrefix.size()), ':');
  for (const Generator& g : generators()) {
    if (g.kind.name != parts[0]) continue;
    const ProceduralArgs args(name, parts[0], std::vector<std::string>(parts.begin() + 1, parts.end()));
    return wrap_geometry(g.make(args), name);
  }
  std::string kinds;
  for (const Generator& g : generators()) kinds += (kinds.empty() ? "" : ", ") + g.kind.name;
  throw InputError(std::string(name), "", fmt::format("unknown procedural scene '{}' (choose from {})", parts[0], kinds));
}

std::filesystem::path resolve_file(std::string_view name, const std::filesystem::path& base) {
  for (std::string_view prefix : kSharedDataPrefixes) {
    if (!name.starts_with(prefix)) continue;
    const std::optional<std::filesystem::path> shared = find_shared_data(base.empty() ? std::filesystem::current_path() : base);
    if (!shared)
      throw InputError(std::string(name), "",
                       "names the shared data folder, which was not found: set TWINRAY_SHARED to it (the folder with "
                       "data/meshes), or place it as 'shared' beside the repository");
    return *shared / name.substr(prefix.size());
  }
  const std::filesystem::path path(name);
  return path.is_absolute() || base.empty() ? path : base / path;
}

}  // namespace

const std::vector<ProceduralKind>& procedural_scene_kinds() {
  static const std::vector<ProceduralKind> kinds = [] {
    std::vector<ProceduralKind> k;
    for (const Generator& g : generators()) k.push_back(g.kind);
    return k;
  }();
  return kinds;
}

bool is_procedural_scene_name(std::string_view name) { return name.starts_with(kProceduralPrefix); }

Scene load_named_scene(std::string_view name, const std::filesystem::path& base) {
  if (is_procedural_scene_name(name)) return load_procedural(name);
  return load_scene(resolve_file(name, base));
}

std::string portable_scene_name(std::string_view name, const std::filesystem::path& base) {
  if (is_procedural_scene_name(name)) return std::string(name);
  for (std::string_view prefix : kSharedDataPrefixes)
    if (name.starts_with(prefix)) return std::string(name);
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::weakly_canonical(resolve_file(name, base), ec);
  return ec ? resolve_file(name, base).string() : absolute.string();
}

}  // namespace twinray
