#include "harness/grade/grade_rays.h"

#include "core/camera/pinhole_camera.h"
#include "core/sampling/rng.h"
#include "core/sampling/warp.h"
#include "harness/crosscheck/axis_rays.h"
#include "harness/crosscheck/ray_generation.h"
#include "harness/crosscheck/ray_set_support.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <map>

namespace twinray::grade {

namespace {

using crosscheck::next2;
using crosscheck::point_in;
using crosscheck::signed_zero;

Ray make(const glm::vec3& org, const glm::vec3& dir, float tmin = 0.0f, float tmax = INFINITY) {
  Ray r;
  r.org = org;
  r.dir = dir;
  r.tmin = tmin;
  r.tmax = tmax;
  return r;
}

}  // namespace

PixelRays camera_pixel_rays(const Scene& scene, std::size_t count) {
  CameraDesc desc = scene.camera;
  const double aspect = static_cast<double>(desc.width) / static_cast<double>(std::max(desc.height, 1));
  const double target = static_cast<double>(std::max<std::size_t>(count, 1));
  const int width = std::max(1, static_cast<int>(std::lround(std::sqrt(target * aspect))));
  const int height = std::max(1, static_cast<int>(std::lround(target / width)));
  desc.width = width;
  desc.height = height;
  const PinholeCamera camera(desc);
  PixelRays out;
  out.width = width;
  out.height = height;
  out.rays.reserve(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) out.rays.push_back(camera.pixel_center_ray(i, j));
  return out;
}

std::vector<Ray> kind_rays(crosscheck::RayKind kind, const Scene& scene, const Backend& hit_source, std::size_t count,
                           std::uint64_t seed) {
  if (kind == crosscheck::RayKind::Camera) return camera_pixel_rays(scene, count).rays;
  return crosscheck::generate_rays(kind, scene, hit_source, count, seed);
}

std::vector<Ray> interval_rays(std::span<const Ray> rays, std::span<const Hit> hits) {
  std::vector<Ray> out;
  out.reserve(4 * rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (!hits[i].found()) continue;
    const Ray& r = rays[i];
    const float t = hits[i].t;
    const float before = t * (1.0f - kIntervalMargin), after = t * (1.0f + kIntervalMargin);
    if (!(before > r.tmin) || !(after < r.tmax)) continue;  // no room on one side: skip the ray
    out.push_back(make(r.org, r.dir, r.tmin, before));  // ends just before the surface
    out.push_back(make(r.org, r.dir, after, r.tmax));   // starts just after it
    out.push_back(make(r.org, r.dir, r.tmin, after));   // ends just after it
    out.push_back(make(r.org, r.dir, before, r.tmax));  // starts just before it
  }
  return out;
}

std::vector<Ray> axis_aligned_rays(const Scene& scene, std::size_t count, std::uint64_t seed) {
  return crosscheck::axis_aligned_rays(scene, count, seed);
}

namespace {

// Area-weighted vertex normals keyed by position (bit for bit), over every mesh: meshes whose faces do not
// share vertex indices (a box of six separate faces) still get one normal per corner, between its faces.
// In double: the cross products of a scene at 1e-30 (about 1e-60) would be 0 in float, and of one at 1e30
// would overflow.
class VertexNormals {
 public:
  explicit VertexNormals(const SceneGeometry& g) {
    for (const TriangleMesh& m : g.meshes)
      for (const glm::uvec3& t : m.indices) {
        const glm::dvec3 p0(m.positions[t[0]]);
        const glm::dvec3 n = glm::cross(glm::dvec3(m.positions[t[1]]) - p0, glm::dvec3(m.positions[t[2]]) - p0);
        for (int k = 0; k < 3; ++k) sums_[key(m.positions[t[k]])] += n;
      }
  }
  // The unit normal at p, or 0 where the faces' normals cancel (or p is no vertex).
  glm::vec3 at(const glm::vec3& p) const {
    const auto it = sums_.find(key(p));
    if (it == sums_.end() || it->second == glm::dvec3(0.0)) return glm::vec3(0.0f);
    return glm::vec3(glm::normalize(it->second));
  }

 private:
  using Key = std::array<std::uint32_t, 3>;
  static Key key(const glm::vec3& p) {
    return {std::bit_cast<std::uint32_t>(p.x), std::bit_cast<std::uint32_t>(p.y), std::bit_cast<std::uint32_t>(p.z)};
  }
  std::map<Key, glm::dvec3> sums_;
};

}  // namespace

std::vector<Ray> watertight_rays(const Scene& scene, std::size_t count, std::uint64_t seed,
                                 std::optional<glm::vec3> origin) {
  Rng rng = Rng::keyed(seed, 0x3a7e, 2);
  const Bounds3 box = crosscheck::scene_box_or_unit(scene);
  const glm::vec3 inside = origin.value_or(box.center());
  const float reach = 2.0f * std::max(box.diagonal(), 1e-3f);
  std::vector<Ray> rays;
  rays.reserve(count);
  const auto& meshes = scene.geometry.meshes;
  if (meshes.empty()) return rays;
  const VertexNormals normals(scene.geometry);
  while (rays.size() < count) {
    const TriangleMesh& mesh = meshes[rng.next_below(static_cast<std::uint32_t>(meshes.size()))];
    if (mesh.indices.empty()) continue;
    const glm::uvec3 tri = mesh.indices[rng.next_below(static_cast<std::uint32_t>(mesh.indices.size()))];
    const glm::vec3 p0 = mesh.positions[tri[0]], p1 = mesh.positions[tri[1]];
    glm::vec3 dir;
    switch (rays.size() % 4) {
      case 0: dir = sample_uniform_sphere(next2(rng)); break;           // anywhere
      case 1: dir = p0 - inside; break;                                 // exactly through a vertex
      case 2: dir = 0.5f * (p0 + p1) - inside; break;                   // through an edge's midpoint
      default: {  // from outside, at a vertex, along its normal: between all its faces, across none of them
        const glm::vec3 out = normals.at(p0);
        if (out == glm::vec3(0.0f)) continue;
        rays.push_back(make(p0 + reach * out, -out));
        continue;
      }
    }
    if (dir == glm::vec3(0.0f)) continue;
    rays.push_back(make(inside, dir));
  }
  return rays;
}

std::vector<Ray> sphere_rays(const Scene& scene, std::size_t count, std::uint64_t seed) {
  Rng rng = Rng::keyed(seed, 0x5bee, 3);
  std::vector<Ray> rays;
  const auto& spheres = scene.geometry.spheres;
  if (spheres.empty()) return rays;
  rays.reserve(count);
  for (std::size_t i = 0; rays.size() < count; ++i) {
    const Sphere& s = spheres[i % spheres.size()];
    const glm::vec3 away = sample_uniform_sphere(next2(rng));
    // A unit vector perpendicular to `away`, for offsets across the disc the sphere shows from there.
    const glm::vec3 helper = std::fabs(away.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    const glm::vec3 across = glm::normalize(glm::cross(away, helper));
    const glm::vec3 from = s.center + (2.0f + 8.0f * rng.next_float()) * s.radius * away;
    const auto disc_point = [&] {
      const glm::vec2 d = sample_concentric_disk(next2(rng)) * 0.9f;
      const glm::vec3 across2 = glm::cross(away, across);
      return s.center + s.radius * (d.x * across + d.y * across2);
    };
    switch ((i / spheres.size()) % 8) {
      case 0: rays.push_back(make(from, disc_point() - from)); break;  // from outside at a point of the disc
      case 7:  // the same with tmin = 1, at the disc inside the sphere: between the roots, only the far one counts
        rays.push_back(make(from, disc_point() - from, 1.0f));
        break;
      case 6: {  // the same from far away, 2,000 to 20,000 radii
        const glm::vec3 far = s.center + (2e3f + 1.8e4f * rng.next_float()) * s.radius * away;
        rays.push_back(make(far, disc_point() - far));
        break;
      }
      case 1:  // from inside
        rays.push_back(make(s.center + 0.5f * s.radius * rng.next_float() * away, sample_uniform_sphere(next2(rng))));
        break;
      case 2: rays.push_back(make(from, s.center + 0.99f * s.radius * across - from)); break;  // just inside the rim
      case 3: rays.push_back(make(from, s.center + 1.01f * s.radius * across - from)); break;  // just outside it
      case 4: rays.push_back(make(from, s.center + s.radius * across - from)); break;          // tangent
      default: rays.push_back(make(from, s.center + 1.5f * s.radius * across - from)); break; // a clear miss
    }
  }
  // Then count / 8 segments inside the balls, from a separate stream so the rays above stay as they were: from
  // within 0.5 r of the centre, a unit direction, tmax 0.4 r, so the segment ends at least 0.1 r inside the
  // surface and crosses no surface of its sphere. Only a test that treats the sphere as a solid ball (any-hit:
  // "the segment overlaps the ball") or reports a root beyond tmax answers a hit on it.
  Rng inner = Rng::keyed(seed, 0x5bee, 6);
  const std::size_t segments = count / 8;
  for (std::size_t i = 0; i < segments; ++i) {
    const Sphere& s = spheres[i % spheres.size()];
    const glm::vec3 org = s.center + 0.5f * s.radius * inner.next_float() * sample_uniform_sphere(next2(inner));
    rays.push_back(make(org, sample_uniform_sphere(next2(inner)), 0.0f, 0.4f * s.radius));
  }
  // Then count / 16 rays that start past their sphere (twelfth round): from outside (2 to 10 r from the centre) at
  // a point of the disc through the centre (within 0.9 r of it), which the ray reaches at t = 1, with tmin 2.5.
  // |dir| >= 1.1 r, so the far root is at most 1 + r / |dir| < 1.91: the whole sphere lies at least 0.59 |dir|
  // (0.65 r) before tmin, and no rounding makes it count. A test that takes a sphere's roots from t = 0 (or from
  // an epsilon) rather than from tmin, in any-hit or closest-hit, answers that sphere; the right answer is
  // whatever lies beyond (often nothing).
  Rng past = Rng::keyed(seed, 0x5bee, 7);
  const std::size_t behind = count / 16;
  for (std::size_t i = 0; i < behind; ++i) {
    const Sphere& s = spheres[i % spheres.size()];
    const glm::vec3 away = sample_uniform_sphere(next2(past));
    const glm::vec3 helper = std::fabs(away.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    const glm::vec3 across = glm::normalize(glm::cross(away, helper)), across2 = glm::cross(away, across);
    const glm::vec3 from = s.center + (2.0f + 8.0f * past.next_float()) * s.radius * away;
    const glm::vec2 d = sample_concentric_disk(next2(past)) * 0.9f;
    const glm::vec3 target = s.center + s.radius * (d.x * across + d.y * across2);
    rays.push_back(make(from, target - from, 2.5f));
  }
  return rays;
}

std::vector<Ray> tie_rays(const Scene& scene, std::size_t count, std::uint64_t seed) {
  Rng rng = Rng::keyed(seed, 0x71e5, 4);
  const Bounds3 around = crosscheck::padded_box(crosscheck::scene_box_or_unit(scene), 0.5f);
  std::vector<Ray> rays;
  const auto& meshes = scene.geometry.meshes;
  if (meshes.empty()) return rays;
  rays.reserve(count);
  while (rays.size() < count) {
    const TriangleMesh& mesh = meshes[rng.next_below(static_cast<std::uint32_t>(meshes.size()))];
    if (mesh.indices.empty()) continue;
    const glm::uvec3 tri = mesh.indices[rng.next_below(static_cast<std::uint32_t>(mesh.indices.size()))];
    // Barycentrics in the triangle shrunk to 70% around its centroid: at least 0.1 from every edge.
    glm::vec3 b = sample_uniform_triangle(next2(rng));
    b = 0.1f + 0.7f * b;
    const glm::vec3 target = b[0] * mesh.positions[tri[0]] + b[1] * mesh.positions[tri[1]] + b[2] * mesh.positions[tri[2]];
    const glm::vec3 org = point_in(around, rng);
    if (target == org) continue;
    rays.push_back(make(org, target - org));
  }
  return rays;
}

std::vector<Ray> deep_tree_rays(const Scene& scene, std::size_t count, std::uint64_t seed,
                                std::optional<glm::vec3> origin) {
  const glm::vec3 org = origin.value_or(glm::vec3(0.0f));
  struct Triangle {
    const TriangleMesh* mesh;
    glm::uvec3 tri;
  };
  // Keyed by the binary exponent of the centroid's distance; a std::map keeps the groups in a fixed order.
  std::map<int, std::vector<Triangle>> groups;
  for (const TriangleMesh& mesh : scene.geometry.meshes) {
    for (const glm::uvec3& tri : mesh.indices) {
      const glm::vec3 centroid = (mesh.positions[tri[0]] + mesh.positions[tri[1]] + mesh.positions[tri[2]]) / 3.0f;
      int exponent = 0;
      std::frexp(glm::length(glm::dvec3(centroid) - glm::dvec3(org)), &exponent);
      groups[exponent].push_back({&mesh, tri});
    }
  }
  std::vector<Ray> rays;
  if (groups.empty()) return rays;
  std::vector<const std::vector<Triangle>*> order;
  for (const auto& [exponent, triangles] : groups) order.push_back(&triangles);
  Rng rng = Rng::keyed(seed, 0xdee9, 5);
  rays.reserve(count);
  // Bounded: on a scene whose every triangle rounds to the origin point, no target differs from it, and the
  // set stays short rather than the loop running forever.
  for (std::size_t attempt = 0; rays.size() < count && attempt < 64 * count; ++attempt) {
    const std::vector<Triangle>& group = *order[rng.next_below(static_cast<std::uint32_t>(order.size()))];
    const Triangle& t = group[rng.next_below(static_cast<std::uint32_t>(group.size()))];
    // Barycentrics at least 0.1 from every edge (as tie_rays): the ray crosses the triangle's interior.
    const glm::vec3 b = 0.1f + 0.7f * sample_uniform_triangle(next2(rng));
    const glm::vec3 target =
        b[0] * t.mesh->positions[t.tri[0]] + b[1] * t.mesh->positions[t.tri[1]] + b[2] * t.mesh->positions[t.tri[2]];
    if (target == org) continue;
    // A unit direction: target - org spans 2^72 in length on a nested scene, and a float test multiplies
    // the direction into products of coordinates that must stay normal floats.
    rays.push_back(make(org, glm::vec3(glm::normalize(glm::dvec3(target) - glm::dvec3(org)))));
  }
  return rays;
}

}  // namespace twinray::grade
