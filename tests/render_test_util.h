#pragma once
// Small programmatic scenes and image statistics shared by the rendering tests.

#include "backends/registry.h"
#include "core/image/image.h"
#include "core/render/renderer.h"
#include "core/scene/scene.h"
#include "core/util/fp_mode.h"

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <tbb/global_control.h>

namespace twinray::test {

inline std::uint32_t add_material(Scene& scene, Material m) {
  scene.materials.push_back(std::move(m));
  return static_cast<std::uint32_t>(scene.materials.size() - 1);
}

inline Material diffuse(glm::vec3 albedo) {
  Material m;
  m.type = MaterialType::Diffuse;
  m.albedo = albedo;
  return m;
}
inline Material mirror(glm::vec3 reflectance) {
  Material m;
  m.type = MaterialType::Mirror;
  m.reflectance = reflectance;
  return m;
}
inline Material glass(float ior) {
  Material m;
  m.type = MaterialType::Glass;
  m.ior = ior;
  return m;
}
inline Material emissive(glm::vec3 radiance, glm::vec3 albedo = glm::vec3(0.0f)) {
  Material m;
  m.type = MaterialType::Emissive;
  m.radiance = radiance;
  m.albedo = albedo;
  return m;
}

inline std::uint32_t next_geom_id(const Scene& scene) { return static_cast<std::uint32_t>(scene.shapes.size()); }

inline void add_sphere(Scene& scene, glm::vec3 center, float radius, std::uint32_t material) {
  Sphere s;
  s.geom_id = next_geom_id(scene);
  s.center = center;
  s.radius = radius;
  scene.geometry.spheres.push_back(s);
  scene.shapes.push_back({"sphere", ShapeKind::Sphere, material, {}});
}

// Triangles given as a flat list of positions, three per triangle, counter-clockwise seen from the front.
inline void add_triangles(Scene& scene, const std::vector<glm::vec3>& corners, std::uint32_t material) {
  TriangleMesh mesh;
  mesh.geom_id = next_geom_id(scene);
  mesh.positions = corners;
  mesh.positions.reserve(corners.size() + 1);  // Embree reads 4 bytes past the last vertex
  for (std::uint32_t i = 0; i + 2 < corners.size(); i += 3) mesh.indices.push_back({i, i + 1, i + 2});
  scene.geometry.meshes.push_back(std::move(mesh));
  scene.shapes.push_back({"mesh", ShapeKind::Mesh, material, {}});
}

// A parallelogram p, p + a, p + a + b, p + b; its front (normal cross(a, b)) is the emitting/visible side.
inline void add_quad(Scene& scene, glm::vec3 p, glm::vec3 a, glm::vec3 b, std::uint32_t material) {
  add_triangles(scene, {p, p + a, p + a + b, p, p + a + b, p + b}, material);
}

// An axis-aligned box whose faces point inward (inward = true) or outward.
inline void add_box(Scene& scene, glm::vec3 lo, glm::vec3 hi, std::uint32_t material, bool inward) {
  const glm::vec3 d = hi - lo;
  const glm::vec3 X(d.x, 0, 0), Y(0, d.y, 0), Z(0, 0, d.z);
  // Each face as (corner, edge a, edge b) with cross(a, b) pointing outward.
  struct Face { glm::vec3 p, a, b; };
  const Face faces[6] = {
      {lo, Z, Y}, {lo + X, Y, Z},   // -X, +X
      {lo, X, Z}, {lo + Y, Z, X},   // -Y, +Y
      {lo, Y, X}, {lo + Z, X, Y}};  // -Z, +Z
  for (const Face& f : faces) {
    if (inward) add_quad(scene, f.p, f.b, f.a, material);
    else add_quad(scene, f.p, f.a, f.b, material);
  }
}

inline Scene empty_scene(glm::vec3 eye, glm::vec3 target, glm::vec3 up, float vfov, int w, int h) {
  Scene s;
  s.camera.position = eye;
  s.camera.look_at = target;
  s.camera.up = up;
  s.camera.vfov_deg = vfov;
  s.camera.width = w;
  s.camera.height = h;
  return s;
}

inline void constant_environment(Scene& scene, glm::vec3 radiance) {
  scene.environment.type = EnvironmentType::Constant;
  scene.environment.radiance = radiance;
}

struct Rendered {
  Image mean;
  Image variance_of_mean;
  Image albedo;  // aux albedo (first hit, mean over samples)
  RenderFeatures features;
  RenderStats stats;
};

// The named backend, built over the scene's geometry.
inline std::unique_ptr<Backend> built_backend(const Scene& scene, const std::string& name = "bvh") {
  std::unique_ptr<Backend> backend = make_backend(name);
  backend->build(scene.geometry);
  return backend;
}

inline Rendered render_scene(const Scene& scene, const RenderOptions& options, const std::string& backend_name = "bvh") {
  const ScopedFlushDenormals ftz;
  const std::unique_ptr<Backend> backend = built_backend(scene, backend_name);
  RenderOptions opt = options;
  opt.show_progress = false;
  opt.aux.albedo = true;
  const RenderSetup setup(scene, opt, backend->traits());
  const RenderResult r = render(setup, *backend);
  return {r.film.mean_image(), r.film.variance_of_mean_image(), r.film.albedo_image(), setup.features(), r.stats};
}

// Mean of one channel over the pixels selected by `keep`, with its standard error from the per-pixel
// variances of the mean (pixels are independent).
struct RegionEstimate {
  double mean = 0.0;
  double standard_error = 0.0;
  std::size_t pixels = 0;
};
inline RegionEstimate region_mean(const Rendered& r, int channel, const std::function<bool(int, int)>& keep) {
  RegionEstimate e;
  double var = 0.0;
  for (int y = 0; y < r.mean.height; ++y)
    for (int x = 0; x < r.mean.width; ++x) {
      if (!keep(x, y)) continue;
      e.mean += r.mean.at(x, y, channel);
      var += r.variance_of_mean.at(x, y, channel);
      ++e.pixels;
    }
  if (e.pixels == 0) return e;
  const double n = static_cast<double>(e.pixels);
  e.mean /= n;
  e.standard_error = std::sqrt(var) / n;
  return e;
}

// Relative MSE of a against reference b: mean over pixels and channels of (a - b)^2 / (b^2 + eps).
inline double rel_mse(const Image& a, const Image& b, double eps = 1e-2) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    const double d = static_cast<double>(a.data[i]) - static_cast<double>(b.data[i]);
    sum += d * d / (static_cast<double>(b.data[i]) * b.data[i] + eps);
  }
  return sum / static_cast<double>(a.data.size());
}

inline glm::dvec3 image_mean(const Image& img) {
  glm::dvec3 s(0.0);
  for (std::size_t i = 0; i < img.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) s[c] += img.data[i * static_cast<std::size_t>(img.channels) + static_cast<std::size_t>(c)];
  return s / static_cast<double>(img.pixel_count());
}

}  // namespace twinray::test
