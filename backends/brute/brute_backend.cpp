#include "backends/brute/brute_backend.h"

#include "core/intersect/sphere_robust.h"
#include "core/intersect/triangle_watertight.h"

#include <algorithm>
#include <chrono>
#include <cstdint>

namespace twinray {

namespace {

class BruteBackend final : public Backend {
 public:
  std::string_view name() const override { return "brute"; }

  BackendTraits traits() const override {
    // Nodes visited stays 0 (there are none); primitives tested is counted exactly.
    return {.counts_traversal = true, .honours_ties = true, .watertight = true};
  }

  void build(const SceneGeometry& geometry) override {
    const auto start = std::chrono::steady_clock::now();
    geometry_ = &geometry;
    stats_ = {};
    stats_.triangles = geometry.triangle_count();
    stats_.spheres = geometry.sphere_count();
    stats_.built_triangles = geometry.has_triangles();
    stats_.built_spheres = geometry.has_spheres();
    stats_.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  BuildStats build_stats() const override { return stats_; }

  bool intersect(const Ray& ray, Hit& hit, QueryStats* stats) const override {
    hit = Hit{};
    if (stats) ++stats->queries;
    if (geometry_ == nullptr || !is_valid_ray(ray)) return false;
    const TriangleRay tri_ray = make_triangle_ray(ray.org, ray.dir);
    // The winner's shape, for the attributes computed once at the end.
    const TriangleMesh* best_mesh = nullptr;
    const Sphere* best_sphere = nullptr;
    // The end of the interval still searched: the closest hit's t so far (closed, so an equidistant hit still
    // reaches `precedes`). Kept in a local, and the mesh's arrays too: stores to `hit` could alias them, and
    // the loop would reload them for every triangle.
    float tmax = ray.tmax;
    for (const TriangleMesh& mesh : geometry_->meshes) {
      const glm::uvec3* indices = mesh.indices.data();
      const glm::vec3* p = mesh.positions.data();
      const std::size_t count = mesh.indices.size();
      for (std::size_t i = 0; i < count; ++i) {
        const glm::uvec3 tri = indices[i];
        float t;
        // t only: the winner's u, v are computed once, at the end.
        if (!intersect_triangle_t(tri_ray, p[tri.x], p[tri.y], p[tri.z], ray.tmin, tmax, t)) continue;
        const auto prim_id = static_cast<std::uint32_t>(i);
        if (!precedes(t, mesh.geom_id, prim_id, hit)) continue;
        hit.t = tmax = t;
        hit.geom_id = mesh.geom_id;
        hit.prim_id = prim_id;
        best_mesh = &mesh;
        best_sphere = nullptr;
      }
      if (stats) stats->primitives_tested += count;
    }
    for (const Sphere& s : geometry_->spheres) {
      float t;
      if (!intersect_sphere(ray.org, ray.dir, s.center, s.radius, ray.tmin, tmax, t)) continue;
      if (!precedes(t, s.geom_id, 0, hit)) continue;
      hit.t = tmax = t;
      hit.geom_id = s.geom_id;
      hit.prim_id = 0;
      best_mesh = nullptr;
      best_sphere = &s;
    }
    if (stats) stats->primitives_tested += geometry_->spheres.size();

    if (best_sphere != nullptr) {
      sphere_hit_attributes(ray.org, ray.dir, hit.t, best_sphere->center, best_sphere->radius, hit.ng, hit.u, hit.v);
    } else if (best_mesh != nullptr) {
      const glm::uvec3& tri = best_mesh->indices[hit.prim_id];
      const std::vector<glm::vec3>& p = best_mesh->positions;
      triangle_hit_attributes(tri_ray, p[tri.x], p[tri.y], p[tri.z], hit.t, hit.u, hit.v, hit.ng);
    }
    return hit.found();
  }

  bool occluded(const Ray& ray, QueryStats* stats) const override {
    if (stats) ++stats->queries;
    if (geometry_ == nullptr || !is_valid_ray(ray)) return false;
    const TriangleRay tri_ray = make_triangle_ray(ray.org, ray.dir);
    std::uint64_t tested = 0;
    bool found = false;
    for (const TriangleMesh& mesh : geometry_->meshes) {
      const glm::vec3* p = mesh.positions.data();
      for (const glm::uvec3& tri : mesh.indices) {
        ++tested;
        if (intersect_triangle_any(tri_ray, p[tri.x], p[tri.y], p[tri.z], ray.tmin, ray.tmax)) {
          found = true;
          break;
        }
      }
      if (found) break;
    }
    if (!found) {
      for (const Sphere& s : geometry_->spheres) {
        ++tested;
        float t;
        if (intersect_sphere(ray.org, ray.dir, s.center, s.radius, ray.tmin, ray.tmax, t)) {
          found = true;
          break;
        }
      }
    }
    if (stats) stats->primitives_tested += tested;
    return found;
  }

  using Backend::intersect;
  using Backend::occluded;

 private:
  const SceneGeometry* geometry_ = nullptr;
  BuildStats stats_;
};

}  // namespace

std::unique_ptr<Backend> make_brute_backend() { return std::make_unique<BruteBackend>(); }

}  // namespace twinray
