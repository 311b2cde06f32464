#include "harness/crosscheck/ray_generation.h"

#include "harness/crosscheck/axis_rays.h"
#include "harness/crosscheck/ray_set_support.h"

#include "core/camera/pinhole_camera.h"
#include "core/geometry/ray_offset.h"
#include "core/sampling/rng.h"
#include "core/sampling/warp.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace twinray::crosscheck {

namespace {

// The scene box grown by 10% of its diagonal on every side, so uniform rays also start outside it.
// A flat or point-like scene still gets a box of positive volume. Nothing absolute: a scene of size 1e-30
// gets rays at its own scale (the 1e-3 floor applies only to a single point at the origin).
Bounds3 padded_bounds(const Scene& scene) {
  Bounds3 b = scene.geometry.bounds();
  if (b.empty()) b = Bounds3::of_point(glm::vec3(0.0f));
  const float diagonal = b.diagonal();
  const auto distance = static_cast<float>(glm::length(glm::dvec3(b.center())));
  const float pad = diagonal > 0.0f || distance > 0.0f ? std::max(0.1f * diagonal, 1e-3f * distance) : 1e-3f;
  b.lo -= glm::vec3(pad);
  b.hi += glm::vec3(pad);
  return b;
}

Ray camera_ray(const PinholeCamera& camera, std::size_t index, std::size_t count, Rng& rng) {
  // Stratified over the pixels in scanline order: ray k lands in pixel floor(k * W*H / count), jittered
  // inside it, so any count covers the whole image.
  const std::size_t pixels = static_cast<std::size_t>(camera.width()) * static_cast<std::size_t>(camera.height());
  const std::size_t pixel = static_cast<std::size_t>((static_cast<long double>(index) * pixels) / count);
  const auto px = static_cast<int>(pixel % static_cast<std::size_t>(camera.width()));
  const auto py = static_cast<int>(pixel / static_cast<std::size_t>(camera.width()));
  const float u = (static_cast<float>(px) + rng.next_float()) / static_cast<float>(camera.width());
  const float v = 1.0f - (static_cast<float>(py) + rng.next_float()) / static_cast<float>(camera.height());
  return camera.generate_ray(u, v);
}

// Surface points seen from the camera, with the normal flipped to face the viewer.
struct SurfacePoint {
  glm::vec3 p;
  glm::vec3 n;
};

class FirstHitSampler {
 public:
  FirstHitSampler(const Scene& scene, const Backend& backend, std::size_t count, Rng& rng)
      : camera_(scene.camera), backend_(backend), count_(std::max<std::size_t>(count, 1)), rng_(rng) {}

  // A visible surface point seen through a random pixel, or nothing after many consecutive misses (a
  // view with (almost) nothing in it).
  bool next(SurfacePoint& out) {
    for (int attempt = 0; attempt < 4096; ++attempt) {
      const std::size_t stratum = static_cast<std::size_t>(rng_.next_double() * static_cast<double>(count_));
      const Ray ray = camera_ray(camera_, std::min(stratum, count_ - 1), count_, rng_);
      Hit hit;
      if (!backend_.intersect(ray, hit)) continue;
      const glm::vec3 p = ray.at(hit.t);
      const glm::vec3 n = glm::dot(hit.ng, ray.dir) > 0.0f ? -hit.ng : hit.ng;
      out = {offset_ray_origin(p, n), n};
      return true;
    }
    return false;
  }

 private:
  PinholeCamera camera_;
  const Backend& backend_;
  std::size_t count_;
  Rng& rng_;
};

// Points on emitters, chosen in proportion to area, to aim shadow rays at.
class EmitterPointSampler {
 public:
  explicit EmitterPointSampler(const Scene& scene) : scene_(scene) {
    double total = 0.0;
    for (std::size_t m = 0; m < scene.geometry.meshes.size(); ++m) {
      const TriangleMesh& mesh = scene.geometry.meshes[m];
      if (scene.material_of(mesh.geom_id).type != MaterialType::Emissive) continue;
      for (std::size_t t = 0; t < mesh.indices.size(); ++t) {
        const glm::uvec3 tri = mesh.indices[t];
        const glm::dvec3 p0(mesh.positions[tri[0]]);
        const glm::dvec3 c = glm::cross(glm::dvec3(mesh.positions[tri[1]]) - p0, glm::dvec3(mesh.positions[tri[2]]) - p0);
        total += 0.5 * glm::length(c);
        entries_.push_back({total, m, t});
      }
    }
    for (std::size_t s = 0; s < scene.geometry.spheres.size(); ++s) {
      const Sphere& sphere = scene.geometry.spheres[s];
      if (scene.material_of(sphere.geom_id).type != MaterialType::Emissive) continue;
      total += 4.0 * 3.14159265358979323846 * double(sphere.radius) * double(sphere.radius);
      entries_.push_back({total, kSphere, s});
    }
  }

  bool empty() const { return entries_.empty() || !(entries_.back().cumulative_area > 0.0); }

  SurfacePoint sample(Rng& rng) const {
    const double x = rng.next_double() * entries_.back().cumulative_area;
    const auto it = std::upper_bound(entries_.begin(), entries_.end(), x,
                                     [](double value, const Entry& e) { return value < e.cumulative_area; });
    const Entry& e = it == entries_.end() ? entries_.back() : *it;
    if (e.mesh == kSphere) {
      const Sphere& s = scene_.geometry.spheres[e.index];
      const glm::vec3 d = sample_uniform_sphere(next2(rng));
      return {s.center + s.radius * d, d};
    }
    const TriangleMesh& mesh = scene_.geometry.meshes[e.mesh];
    const glm::uvec3 tri = mesh.indices[e.index];
    const glm::vec3 b = sample_uniform_triangle(next2(rng));
    const glm::vec3 p0 = mesh.positions[tri[0]], p1 = mesh.positions[tri[1]], p2 = mesh.positions[tri[2]];
    const glm::dvec3 n = glm::cross(glm::dvec3(p1) - glm::dvec3(p0), glm::dvec3(p2) - glm::dvec3(p0));
    return {b[0] * p0 + b[1] * p1 + b[2] * p2, glm::vec3(glm::normalize(n))};
  }

 private:
  static constexpr std::size_t kSphere = static_cast<std::size_t>(-1);
  struct Entry {
    double cumulative_area;
    std::size_t mesh;   // kSphere for spheres
    std::size_t index;  // triangle or sphere index
  };
  const Scene& scene_;
  std::vector<Entry> entries_;
};

}  // namespace

std::vector<Ray> generate_rays(RayKind kind, const Scene& scene, const Backend& hit_source, std::size_t count,
                               std::uint64_t seed) {
  std::vector<Ray> rays;
  rays.reserve(count);
  Rng rng = Rng::keyed(seed, static_cast<std::uint64_t>(kind), 0x7277a1);
  const Bounds3 box = padded_bounds(scene);

  switch (kind) {
    case RayKind::Camera: {
      const PinholeCamera camera(scene.camera);
      for (std::size_t i = 0; i < count; ++i) rays.push_back(camera_ray(camera, i, count, rng));
      break;
    }
    case RayKind::Uniform: {
      // From a random point of the padded box toward another: every ray crosses the scene's bounds.
      while (rays.size() < count) {
        Ray r;
        r.org = point_in(box, rng);
        r.dir = point_in(box, rng) - r.org;
        // Exactly zero, and normalised in double: for a scene at 1e-30 the float squared length is 0.
        if (r.dir == glm::vec3(0.0f)) continue;
        r.dir = glm::vec3(glm::normalize(glm::dvec3(r.dir)));
        rays.push_back(r);
      }
      break;
    }
    case RayKind::Diffuse: {
      FirstHitSampler surfaces(scene, hit_source, count, rng);
      SurfacePoint sp;
      while (rays.size() < count && surfaces.next(sp)) {
        Ray r;
        r.org = sp.p;
        r.dir = Frame::from_normal(sp.n).to_world(sample_cosine_hemisphere(next2(rng)));
        rays.push_back(r);
      }
      break;
    }
    case RayKind::Shadow: {
      FirstHitSampler surfaces(scene, hit_source, count, rng);
      const EmitterPointSampler emitters(scene);
      SurfacePoint sp;
      while (rays.size() < count && surfaces.next(sp)) {
        glm::vec3 target;
        if (emitters.empty()) {
          target = point_in(box, rng);
        } else {
          // The target is lifted off the emitter toward the shading point, so the segment [0, 1] ends
          // just before the emitter's own surface without any global epsilon.
          const SurfacePoint light = emitters.sample(rng);
          const glm::vec3 toward = glm::dot(light.n, sp.p - light.p) >= 0.0f ? light.n : -light.n;
          target = offset_ray_origin(light.p, toward);
        }
        Ray r;
        r.org = sp.p;
        r.dir = target - sp.p;
        if (r.dir == glm::vec3(0.0f)) continue;
        r.tmin = 0.0f;
        r.tmax = 1.0f;
        rays.push_back(r);
      }
      break;
    }
    case RayKind::Axis:
      rays = axis_aligned_rays(scene, count, seed);
      break;
  }
  return rays;
}

}  // namespace twinray::crosscheck
