#include "harness/crosscheck/hit_comparison.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace twinray::crosscheck {

std::string_view to_string(MismatchClass c) {
  switch (c) {
    case MismatchClass::Edge: return "edge";
    case MismatchClass::Tie: return "tie";
    case MismatchClass::Genuine: return "genuine";
  }
  return "?";
}

GeometryIndex::GeometryIndex(const SceneGeometry& geometry) : geometry_(geometry) {
  const std::uint32_t end = geometry.geom_id_end();
  mesh_of_geom_.assign(end, -1);
  sphere_of_geom_.assign(end, -1);
  for (std::size_t i = 0; i < geometry.meshes.size(); ++i) mesh_of_geom_[geometry.meshes[i].geom_id] = static_cast<std::int64_t>(i);
  for (std::size_t i = 0; i < geometry.spheres.size(); ++i) sphere_of_geom_[geometry.spheres[i].geom_id] = static_cast<std::int64_t>(i);
  diagonal_ = geometry.bounds().diagonal();
}

const TriangleMesh* GeometryIndex::mesh(std::uint32_t geom_id) const {
  if (geom_id >= mesh_of_geom_.size() || mesh_of_geom_[geom_id] < 0) return nullptr;
  return &geometry_.meshes[static_cast<std::size_t>(mesh_of_geom_[geom_id])];
}

const Sphere* GeometryIndex::sphere(std::uint32_t geom_id) const {
  if (geom_id >= sphere_of_geom_.size() || sphere_of_geom_[geom_id] < 0) return nullptr;
  return &geometry_.spheres[static_cast<std::size_t>(sphere_of_geom_[geom_id])];
}

namespace {

double world_tolerance(const GeometryIndex& index, const glm::dvec3& p) {
  return kAbsWorld * (static_cast<double>(index.diagonal()) + glm::length(p));
}

// Smallest distance, in world units, from the hit point to the triangle's edges: barycentric * altitude.
double distance_to_edges(const TriangleMesh& mesh, std::uint32_t prim, double u, double v) {
  const glm::uvec3 tri = mesh.indices[prim];
  const glm::dvec3 p0 = mesh.positions[tri[0]], p1 = mesh.positions[tri[1]], p2 = mesh.positions[tri[2]];
  const double twice_area = glm::length(glm::cross(p1 - p0, p2 - p0));
  const double b[3] = {1.0 - u - v, u, v};
  const double opposite[3] = {glm::length(p2 - p1), glm::length(p0 - p2), glm::length(p1 - p0)};
  double d = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (opposite[i] > 0.0) d = std::min(d, std::fabs(b[i]) * twice_area / opposite[i]);
  }
  return d;
}

}  // namespace

bool t_agrees(const GeometryIndex& index, const Ray& ray, float ta, float tb) {
  // The relative term would make an infinite t agree with everything (inf <= 1e-4 * inf): a hit reported at
  // t = +inf is never at the same place as a finite one.
  if (!std::isfinite(ta) || !std::isfinite(tb)) return ta == tb;
  const double dir_len = glm::length(glm::dvec3(ray.dir));
  const double tol = kRelT * std::max<double>(ta, tb) +
                     kAbsWorld * (static_cast<double>(index.diagonal()) + glm::length(glm::dvec3(ray.org))) / dir_len;
  return std::fabs(static_cast<double>(ta) - static_cast<double>(tb)) <= tol;
}

bool hit_is_ambiguous(const GeometryIndex& index, const Ray& ray, const Hit& hit) {
  if (!hit.found()) return false;
  // A hit at t = +inf is on no boundary: its point is infinite, and so would be the tolerance around it.
  if (!std::isfinite(hit.t)) return false;
  // At the ends of the ray's interval a hit may fall just inside for one backend and just outside for another.
  if (t_agrees(index, ray, hit.t, ray.tmin) || (std::isfinite(ray.tmax) && t_agrees(index, ray, hit.t, ray.tmax)))
    return true;
  const glm::dvec3 p = glm::dvec3(ray.org) + static_cast<double>(hit.t) * glm::dvec3(ray.dir);
  if (const TriangleMesh* mesh = index.mesh(hit.geom_id); mesh && hit.prim_id < mesh->indices.size()) {
    return distance_to_edges(*mesh, hit.prim_id, hit.u, hit.v) <= world_tolerance(index, p);
  }
  if (const Sphere* sphere = index.sphere(hit.geom_id)) {
    const glm::dvec3 n = glm::normalize(p - glm::dvec3(sphere->center));
    const double cos_angle = std::fabs(glm::dot(n, glm::normalize(glm::dvec3(ray.dir))));
    return cos_angle < kGrazingCos;
  }
  return false;
}

RayComparison compare_ray(const GeometryIndex& index, const Ray& ray, const Hit& ha, const Hit& hb, bool occluded_a,
                          bool occluded_b) {
  RayComparison r;
  const bool ambiguous = hit_is_ambiguous(index, ray, ha) || hit_is_ambiguous(index, ray, hb);
  if (!ha.found() && !hb.found()) {
    r.identical = true;
  } else if (ha.found() && hb.found() && ha.geom_id == hb.geom_id && ha.prim_id == hb.prim_id) {
    r.rel_t_diff = std::fabs(double(ha.t) - double(hb.t)) / std::max<double>(std::max(ha.t, hb.t), 1e-30);
    r.identical = t_agrees(index, ray, ha.t, hb.t);
    if (!r.identical && ambiguous) r.kind = MismatchClass::Edge;
  } else if (ambiguous) {
    // Checked before ties: neighbours across a shared edge also meet at equal t, and the edge is the
    // better explanation.
    r.kind = MismatchClass::Edge;
  } else if (ha.found() && hb.found() && t_agrees(index, ray, ha.t, hb.t)) {
    r.kind = MismatchClass::Tie;
  }
  if (occluded_a != occluded_b) r.occlusion = ambiguous ? OcclusionClass::Edge : OcclusionClass::Genuine;
  return r;
}

PairComparison compare(const GeometryIndex& index, std::span<const Ray> rays, std::span<const Hit> a,
                       std::span<const Hit> b, std::span<const std::uint8_t> occluded_a,
                       std::span<const std::uint8_t> occluded_b, std::size_t max_examples) {
  PairComparison c;
  c.rays = rays.size();
  const bool with_occlusion = !occluded_a.empty() && !occluded_b.empty();
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Hit& ha = a[i];
    const Hit& hb = b[i];
    c.hits_a += ha.found() ? 1 : 0;
    c.hits_b += hb.found() ? 1 : 0;
    const bool oa = with_occlusion && occluded_a[i] != 0, ob = with_occlusion && occluded_b[i] != 0;
    const RayComparison r = compare_ray(index, rays[i], ha, hb, oa, ob);
    if (r.rel_t_diff) c.max_rel_t_diff = std::max(c.max_rel_t_diff, *r.rel_t_diff);

    if (r.identical) {
      ++c.identical;
    } else {
      c.closest_disputes.push_back(i);
      switch (r.kind) {
        case MismatchClass::Edge: ++c.edge; break;
        case MismatchClass::Tie: ++c.tie; break;
        case MismatchClass::Genuine: ++c.genuine; break;
      }
      if (r.kind == MismatchClass::Genuine && c.examples.size() < max_examples)
        c.examples.push_back({i, r.kind, false, ha, hb, false, false});
    }

    if (with_occlusion) {
      if (oa != ob) c.occlusion_disputes.push_back(i);
      switch (r.occlusion) {
        case OcclusionClass::Agree: ++c.occlusion_agree; break;
        case OcclusionClass::Edge: ++c.occlusion_edge; break;
        case OcclusionClass::Genuine:
          ++c.occlusion_genuine;
          if (c.examples.size() < max_examples) c.examples.push_back({i, MismatchClass::Genuine, true, ha, hb, oa, ob});
          break;
      }
    }
  }
  return c;
}

}  // namespace twinray::crosscheck
