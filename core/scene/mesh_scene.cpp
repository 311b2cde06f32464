#include "core/scene/mesh_scene.h"

#include "core/scene/geometry_cleanup.h"
#include "core/scene/mesh_file.h"

#include <fmt/core.h>
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

namespace {

// The plane reaches this many bounding radii from the mesh's centre in x and z: wide enough to receive the
// shadows and fill the lower part of the default view, small enough that the scene's box (which crosscheck
// draws uniform rays from) stays a few times the mesh's.
constexpr double kGroundHalfWidthRadii = 2.5;
// Gap between the mesh's lowest point and the plane, relative to the bounding radius: far above float
// rounding, far below anything visible; a flat base of the mesh never lies in the plane.
constexpr double kGroundGapRadii = 1e-4;

glm::dvec3 sky_radiance(const glm::dvec3& d, const glm::dvec3& sun, double cos_sun_radius, double sun_radiance) {
  if (glm::dot(d, sun) >= cos_sun_radius) return sun_radiance * glm::dvec3(1.0, 0.96, 0.88);
  const glm::dvec3 horizon(0.80, 0.85, 0.95), zenith(0.20, 0.38, 0.80);
  // Below the horizon the horizon's colour, a little darker: the backdrop beyond the plane's far edge.
  if (d.y < 0.0) return 0.45 * horizon;
  const double t = std::sqrt(d.y);  // fast change near the horizon, slow towards the zenith
  return 0.6 * ((1.0 - t) * horizon + t * zenith);
}

}  // namespace

Image sky_with_sun() {
  const glm::dvec3 sun = glm::normalize(glm::dvec3(kSunDirection[0], kSunDirection[1], kSunDirection[2]));
  const double sun_radius = kSunRadiusDeg * std::numbers::pi / 180.0;
  const double cos_sun_radius = std::cos(sun_radius);
  // Radiance of a disk of angular radius a giving irradiance E at normal incidence: E / (pi sin^2 a).
  const double sun_radiance = kSunIrradiance / (std::numbers::pi * std::sin(sun_radius) * std::sin(sun_radius));
  Image sky(kSkyWidth, kSkyHeight, 3);
  for (int y = 0; y < kSkyHeight; ++y) {
    const double theta = (y + 0.5) / kSkyHeight * std::numbers::pi;
    for (int x = 0; x < kSkyWidth; ++x) {
      // The texel centre's direction (environment_light.h: phi = atan2(x, -z), u = 0.5 + phi / 2 pi).
      const double phi = ((x + 0.5) / kSkyWidth - 0.5) * 2.0 * std::numbers::pi;
      const glm::dvec3 d(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
      const glm::dvec3 L = sky_radiance(d, sun, cos_sun_radius, sun_radiance);
      for (int c = 0; c < 3; ++c) sky.at(x, y, c) = static_cast<float>(L[c]);
    }
  }
  return sky;
}

Scene load_bare_mesh_scene(const std::filesystem::path& mesh_file) {
  Scene scene;
  scene.source = mesh_file;
  scene.from_bare_mesh = true;

  TriangleMesh mesh = read_mesh_file(mesh_file, scene.report);
  mesh.geom_id = 0;
  scene.geometry.meshes.push_back(std::move(mesh));
  clean_geometry(scene.geometry, scene.report);
  const Bounds3 bounds = scene.geometry.bounds();  // of what is left: degenerate triangles do not count

  Material grey;
  grey.name = "mesh";
  grey.type = MaterialType::Diffuse;
  grey.albedo = glm::vec3(0.5f);
  scene.materials.push_back(grey);
  Material floor;
  floor.name = "ground";
  floor.type = MaterialType::Diffuse;
  floor.albedo = glm::vec3(0.32f, 0.30f, 0.28f);
  scene.materials.push_back(floor);

  ShapeInfo shape;
  shape.name = mesh_file.stem().string();
  shape.kind = ShapeKind::Mesh;
  shape.material = 0;
  shape.file = mesh_file;
  scene.shapes.push_back(shape);

  if (!bounds.empty()) {
    const glm::dvec3 lo(bounds.lo), hi(bounds.hi);
    const glm::dvec3 c = 0.5 * (lo + hi);
    const double radius = std::max(glm::length(0.5 * (hi - lo)), 1e-5 * std::max({std::abs(c.x), std::abs(c.y), std::abs(c.z), 1e-30}));
    const double half = kGroundHalfWidthRadii * radius;
    const auto y = static_cast<float>(lo.y - kGroundGapRadii * radius);
    TriangleMesh ground;
    ground.geom_id = 1;
    ground.positions = {{static_cast<float>(c.x - half), y, static_cast<float>(c.z - half)},
                        {static_cast<float>(c.x - half), y, static_cast<float>(c.z + half)},
                        {static_cast<float>(c.x + half), y, static_cast<float>(c.z + half)},
                        {static_cast<float>(c.x + half), y, static_cast<float>(c.z - half)}};
    ground.indices = {{0, 1, 2}, {0, 2, 3}};  // front (counter-clockwise) faces +Y
    ensure_vertex_padding(ground.positions);
    scene.geometry.meshes.push_back(std::move(ground));
    scene.shapes.push_back({"ground plane", ShapeKind::Mesh, 1, {}});
    scene.additions.push_back(fmt::format("ground plane at y = {:.6g}, {:.6g} wide, albedo 0.32 (geometry id 1)", y, 2.0 * half));
  }

  scene.environment.type = EnvironmentType::Image;
  scene.environment.image = "sky-with-sun";
  scene.environment.pixels = std::make_shared<const Image>(sky_with_sun());
  scene.additions.push_back(fmt::format("sky with a sun ({}x{} procedural map, sun {} degrees wide from the upper left)",
                                        kSkyWidth, kSkyHeight, 2.0 * kSunRadiusDeg));
  scene.additions.push_back(fmt::format("mid-grey albedo {} on the mesh", grey.albedo.x));

  // Framed on the mesh alone: the plane is the floor, not part of the subject.
  scene.camera = framing_camera(bounds, 640, 480, 40.0f);
  scene.render = RenderSettings{};
  scene.render.spp = 16;
  scene.render.max_depth = -1;
  return scene;
}

}  // namespace twinray
