#pragma once
// A loaded scene: camera, materials, shapes (whose geometry lives in `geometry`), environment and render
// settings. Produced by load_scene() (core/scene/scene_loader.h) from a JSON scene or a bare OBJ/PLY mesh.

#include "core/geometry/scene_geometry.h"
#include "core/image/image.h"

#include <glm/vec3.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace twinray {

struct CameraDesc {
  glm::vec3 position{0.0f, 0.0f, 1.0f};
  glm::vec3 look_at{0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float vfov_deg = 40.0f;  // full vertical field of view
  int width = 256;
  int height = 256;
};

enum class MaterialType { Diffuse, Mirror, Glass, Emissive };

struct Material {
  std::string name;
  MaterialType type = MaterialType::Diffuse;
  glm::vec3 albedo{0.0f};       // Diffuse: Lambertian reflectance. Emissive: optional diffuse reflectance.
  glm::vec3 reflectance{1.0f};  // Mirror
  float ior = 1.5f;             // Glass: interior index of refraction, exterior is 1
  glm::vec3 radiance{0.0f};     // Emissive: one-sided, on the front (geometric normal) side
  // Diffuse, Mirror, and an Emissive's albedo: false makes the surface black seen from its back (the side
  // its geometric normal points away from), like Mitsuba 3's BSDFs without `twosided`. Glass has two sides
  // by nature and ignores it.
  bool two_sided = true;
};

enum class ShapeKind { Mesh, Sphere };

// One entry per geometry id (Scene::shapes[geom_id]).
struct ShapeInfo {
  std::string name;            // from the scene, or "shape N"
  ShapeKind kind = ShapeKind::Mesh;
  std::uint32_t material = 0;  // index into Scene::materials
  std::filesystem::path file;  // mesh file, empty for inline meshes and spheres
};

enum class EnvironmentType { None, Constant, Image };

// How an image environment turns texels into radiance (docs/environment.md):
//   Nearest:  piecewise constant, texel (x, y) covers u in [x, x+1] / width, theta in [y, y+1] pi / height.
//   Bilinear: Mitsuba 3's `envmap` lookup: texel centres at u = (x + 0.5) / width (periodic in u) and
//             theta = y pi / (height - 1) (the first row at the zenith, the last at the nadir), radiance
//             interpolated bilinearly between the four surrounding centres.
enum class EnvironmentFilter { Nearest, Bilinear };

struct Environment {
  EnvironmentType type = EnvironmentType::None;
  glm::vec3 radiance{0.0f};       // Constant
  std::filesystem::path image;    // Image: latitude-longitude .hdr/.exr, top row = +Y (zenith)
  float rotation_deg = 0.0f;      // Image: rotation about +Y
  float scale = 1.0f;             // Image: radiance multiplier
  EnvironmentFilter filter = EnvironmentFilter::Nearest;  // Image: texel lookup
  // Image: the texels in memory (a procedural map, such as the sky of a bare mesh); when set, `image` is
  // only the map's name and no file is read.
  std::shared_ptr<const Image> pixels;
};

struct RenderSettings {
  int spp = 16;
  int max_depth = -1;  // Mitsuba 3 convention: 1 = emitters only, 2 = direct only, -1 = unlimited
  int rr_depth = 5;    // Russian roulette from this many segments on (Mitsuba's rr_depth)
  std::uint64_t seed = 0;
};

// What the loaders dropped: never fatal, always reported (twinray info).
struct LoadReport {
  std::size_t degenerate_triangles = 0;  // zero area or repeated vertex
  std::size_t nonfinite_triangles = 0;   // a vertex with NaN/Inf (programmatic geometry only: files reject them)
  std::size_t polygons_triangulated = 0; // OBJ faces with more than three vertices
};

struct Scene {
  std::filesystem::path source;  // the scene or mesh file it was loaded from
  bool from_bare_mesh = false;   // true when a bare OBJ/PLY was wrapped in a default scene
  std::vector<std::string> additions;  // what the default scene added around a bare mesh (twinray info)
  CameraDesc camera;
  std::vector<Material> materials;
  std::vector<ShapeInfo> shapes;  // indexed by geometry id
  SceneGeometry geometry;
  Environment environment;
  RenderSettings render;
  LoadReport report;

  const Material& material_of(std::uint32_t geom_id) const { return materials[shapes[geom_id].material]; }
  bool has_emitters() const;  // any shape with an emissive material
};

inline bool Scene::has_emitters() const {
  for (const ShapeInfo& s : shapes)
    if (materials[s.material].type == MaterialType::Emissive) return true;
  return false;
}

}  // namespace twinray
