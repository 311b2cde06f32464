#include "core/scene/mesh_scene.h"

#include "core/scene/geometry_cleanup.h"
#include "core/scene/mesh_file.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace twinray {

CameraDesc framing_camera(const Bounds3& bounds, int width, int height, float vfov_deg) {
  // From +Z, raised and shifted a little so that the three visible faces of a box all show.
  const glm::dvec3 direction = glm::normalize(glm::dvec3(0.3, 0.4, 1.0));
  glm::dvec3 center(0.0);
  double radius = 1.0;  // empty geometry: any sensible view
  if (!bounds.empty()) {
    center = glm::dvec3(bounds.center());
    const glm::dvec3 half_extent = 0.5 * (glm::dvec3(bounds.hi) - glm::dvec3(bounds.lo));
    radius = glm::length(half_extent);  // bounding sphere of the box; > 0 for a flat (2D) mesh too
    // A single point (or a box so small that float cannot place a camera apart from it): use a radius a
    // few float ulps of the position wide so the camera sits at a distinct, finite position.
    const double magnitude = std::max({std::abs(center.x), std::abs(center.y), std::abs(center.z), 1e-30});
    radius = std::max(radius, 1e-5 * magnitude);
  }
  // The sphere fits the vertical field of view exactly when distance = radius / sin(fov / 2); the image is
  // at least as wide as tall here, so it fits horizontally too.
  const double half_fov = 0.5 * static_cast<double>(vfov_deg) * std::numbers::pi / 180.0;
  const double aspect = static_cast<double>(width) / static_cast<double>(height);
  const double fit = std::min(std::sin(half_fov), std::sin(std::atan(std::tan(half_fov) * aspect)));
  const double distance = radius / fit;

  CameraDesc camera;
  camera.position = glm::vec3(center + distance * direction);
  camera.look_at = glm::vec3(center);
  camera.up = glm::vec3(0.0f, 1.0f, 0.0f);
  camera.vfov_deg = vfov_deg;
  camera.width = width;
  camera.height = height;
  return camera;
}

Scene load_bare_mesh_scene(const std::filesystem::path& mesh_file) {
  Scene scene;
  scene.source = mesh_file;
  scene.from_bare_mesh = true;

  TriangleMesh mesh = read_mesh_file(mesh_file, scene.report);
  mesh.geom_id = 0;
  scene.geometry.meshes.push_back(std::move(mesh));
  clean_geometry(scene.geometry, scene.report);

  Material white;
  white.name = "default";
  white.type = MaterialType::Diffuse;
  white.albedo = glm::vec3(0.8f);
  scene.materials.push_back(white);

  ShapeInfo shape;
  shape.name = mesh_file.stem().string();
  shape.kind = ShapeKind::Mesh;
  shape.material = 0;
  shape.file = mesh_file;
  scene.shapes.push_back(shape);

  scene.environment.type = EnvironmentType::Constant;
  scene.environment.radiance = glm::vec3(1.0f);

  scene.camera = framing_camera(scene.geometry.bounds(), 640, 480, 40.0f);
  scene.render = RenderSettings{};
  scene.render.spp = 16;
  scene.render.max_depth = -1;
  return scene;
}

}  // namespace twinray
