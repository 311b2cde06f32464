#include "harness/crosscheck/axis_rays.h"

#include "harness/crosscheck/ray_set_support.h"
#include "core/sampling/warp.h"

#include <cmath>

namespace twinray::crosscheck {

std::vector<Ray> axis_aligned_rays(const Scene& scene, std::size_t count, std::uint64_t seed) {
  Rng rng = Rng::keyed(seed, 0xa715, 1);
  const Bounds3 tight = scene_box_or_unit(scene);
  const Bounds3 around = padded_box(tight, 0.1f);
  std::vector<glm::vec3> vertices;
  for (const TriangleMesh& m : scene.geometry.meshes) vertices.insert(vertices.end(), m.positions.begin(), m.positions.end());
  // Six kinds in turn; the two through vertices only where there are vertices.
  const std::size_t kinds = vertices.empty() ? 4 : 6;
  std::vector<Ray> rays;
  rays.reserve(count);
  for (std::size_t i = 0; rays.size() < count; ++i) {
    const int axis = static_cast<int>(rng.next_below(3));
    const bool negative = (rng.next_u32() & 1u) != 0;
    glm::vec3 dir, org;
    switch (i % kinds) {
      case 4: {  // along an axis through a vertex, from outside the scene's box
        const glm::vec3 v = vertices[rng.next_below(static_cast<std::uint32_t>(vertices.size()))];
        dir = {signed_zero(rng), signed_zero(rng), signed_zero(rng)};
        dir[axis] = negative ? -1.0f : 1.0f;
        org = v;
        org[axis] = negative ? around.hi[axis] : around.lo[axis];
        break;
      }
      case 5: {  // in a coordinate plane through a vertex
        const glm::vec3 v = vertices[rng.next_below(static_cast<std::uint32_t>(vertices.size()))];
        dir = sample_uniform_sphere(next2(rng));
        dir[axis] = signed_zero(rng);
        if (dir == glm::vec3(0.0f)) continue;
        org = point_in(around, rng);
        org[axis] = v[axis];
        break;
      }
      case 0:  // along an axis; the other two components are +0 or -0
        dir = {signed_zero(rng), signed_zero(rng), signed_zero(rng)};
        dir[axis] = negative ? -1.0f : 1.0f;
        org = point_in(around, rng);
        break;
      case 1: {  // in a coordinate plane: one component exactly +0 or -0
        dir = sample_uniform_sphere(next2(rng));
        dir[axis] = signed_zero(rng);
        if (dir == glm::vec3(0.0f)) continue;
        org = point_in(around, rng);
        break;
      }
      default: {  // from exactly on a face of the bounding box, pointing inward (along the axis, or in a plane)
        org = point_in(tight, rng);
        org[axis] = negative ? tight.hi[axis] : tight.lo[axis];
        const float inward = negative ? -1.0f : 1.0f;
        if (i % kinds == 2) {
          dir = {signed_zero(rng), signed_zero(rng), signed_zero(rng)};
          dir[axis] = inward;
        } else {
          dir = sample_uniform_sphere(next2(rng));
          dir[axis] = inward * std::max(std::fabs(dir[axis]), 0.1f);
          dir[(axis + 1 + static_cast<int>(rng.next_below(2))) % 3] = signed_zero(rng);
        }
        break;
      }
    }
    Ray ray;
    ray.org = org;
    ray.dir = dir;
    rays.push_back(ray);
  }
  return rays;
}

}  // namespace twinray::crosscheck
