// The glue between your BVH and twinray (the C plugin interface of twinray_plugin.h). Nothing to do here
// unless you want twinray's statistics: then count in BVH::hit / any_hit and set the flag below.

#include "bvh.h"
#include "twinray_plugin.h"

#include <cstring>
#include <exception>
#include <new>
#include <vector>

namespace {

Vec3 vertex(const twinray_mesh& mesh, std::size_t triangle, int corner) {
  const float* p = mesh.positions + 3 * static_cast<std::size_t>(mesh.indices[3 * triangle + static_cast<std::size_t>(corner)]);
  return {p[0], p[1], p[2]};
}

Ray to_ray(const twinray_ray* r) {
  Ray ray;
  ray.point = {r->org[0], r->org[1], r->org[2]};
  ray.dir = {r->dir[0], r->dir[1], r->dir[2]};
  ray.dist_bounds[0] = r->tmin;
  ray.dist_bounds[1] = r->tmax;
  return ray;
}

void* create() { return new (std::nothrow) BVH(); }

void destroy(void* self) { delete static_cast<BVH*>(self); }

int build(void* self, const twinray_geometry* geometry, char* error, size_t capacity) {
  try {
    std::vector<Primitive> primitives;
    for (std::size_t m = 0; m < geometry->mesh_count; ++m) {
      const twinray_mesh& mesh = geometry->meshes[m];
      for (std::size_t i = 0; i < mesh.triangle_count; ++i) {
        Primitive p;
        p.kind = Primitive::Kind::Triangle;
        p.triangle = {vertex(mesh, i, 0), vertex(mesh, i, 1), vertex(mesh, i, 2), mesh.geom_id, static_cast<std::uint32_t>(i)};
        primitives.push_back(p);
      }
    }
    for (std::size_t s = 0; s < geometry->sphere_count; ++s) {
      const twinray_sphere& sphere = geometry->spheres[s];
      Primitive p;
      p.kind = Primitive::Kind::Sphere;
      p.sphere = {{sphere.center[0], sphere.center[1], sphere.center[2]}, sphere.radius, sphere.geom_id};
      primitives.push_back(p);
    }
    static_cast<BVH*>(self)->build(std::move(primitives));
    return TWINRAY_OK;
  } catch (const std::exception& e) {
    // No exception may cross the C interface: report it as a failed build.
    if (capacity > 0) {
      std::strncpy(error, e.what(), capacity - 1);
      error[capacity - 1] = '\0';
    }
    return TWINRAY_ERROR;
  }
}

int intersect1(const void* self, const twinray_ray* r, twinray_hit* hit, twinray_query_stats* stats) {
  TraversalStats counted;
  const Trace t = static_cast<const BVH*>(self)->hit(to_ray(r), counted);
  stats->nodes_visited += counted.nodes_visited;
  stats->primitives_tested += counted.primitives_tested;
  if (!t.hit) return 0;
  hit->t = t.distance;
  hit->u = t.u;
  hit->v = t.v;
  hit->geom_id = t.geom_id;
  hit->prim_id = t.prim_id;
  hit->ng[0] = t.normal.x;
  hit->ng[1] = t.normal.y;
  hit->ng[2] = t.normal.z;
  return 1;
}

int occluded1(const void* self, const twinray_ray* r, twinray_query_stats* stats) {
  TraversalStats counted;
  const bool blocked = static_cast<const BVH*>(self)->any_hit(to_ray(r), counted);
  stats->nodes_visited += counted.nodes_visited;
  stats->primitives_tested += counted.primitives_tested;
  return blocked ? 1 : 0;
}

void build_stats(const void* self, twinray_build_stats* stats) {
  const BVH* bvh = static_cast<const BVH*>(self);
  stats->nodes = bvh->node_count();
  stats->sah_cost = bvh->sah_cost();
}

const twinray_plugin_v1 table = {
    TWINRAY_PLUGIN_ABI_VERSION,
    "student-bvh",
    // Claim only what you guarantee: TWINRAY_PLUGIN_COUNTS_TRAVERSAL once hit() and any_hit() fill the
    // stats. (TWINRAY_PLUGIN_WATERTIGHT and TWINRAY_PLUGIN_HONOURS_TIES are for BVHs that guarantee them;
    // with the given Moller-Trumbore triangle test this one is not watertight.)
    0u,
    create,
    destroy,
    build,
    intersect1,
    occluded1,
    nullptr,  // intersect_batch: optional
    nullptr,  // occluded_batch: optional
    build_stats,
};

}  // namespace

TWINRAY_PLUGIN_EXPORT const twinray_plugin_v1* twinray_plugin_entry(void) { return &table; }
