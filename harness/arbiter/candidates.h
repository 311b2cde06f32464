#pragma once
// The primitives near a ray, as the arbiter sees them: for each, whether the ray reaches it (within the
// world tolerance), whether it crosses it exactly (under the contract), where, and whether the crossing is
// on an edge or a silhouette. harness/arbiter/tolerances.h defines the tolerances.

#include "backends/exact/exact_backend.h"
#include "core/geometry/ray.h"
#include "core/geometry/scene_geometry.h"

#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace twinray::arbiter {

struct Candidate {
  PrimitiveRef ref;
  bool sphere = false;
  double scale = 0.0;   // S: the largest coordinate magnitude of the origin and the primitive
  double delta = 0.0;   // kWorld * S
  double distance = 0.0;  // from the ray's line to the primitive (0 when the line passes through it)
  bool near_boundary = false;  // the line passes within delta of an edge (triangle) or the silhouette (sphere)
  unsigned near_edges = 0;     // triangles: bit k set when the line passes within delta of edge k (p_k -> p_k+1)
  bool crossing = false;  // a single crossing exists (triangle not parallel to the line; sphere line meets it)
  bool hit = false;       // the exact answer counts it: the fill rule (or a root) with tmin <= t <= tmax
  float t = 0.0f;         // its correctly rounded t: the contract's root for a hit sphere, else the near root;
                          // a triangle's crossing with its plane
  double t_exact = 0.0;   // the same, to double precision
  double t_other = 0.0;   // spheres: the other root
  double graze_lo = 0.0, graze_hi = 0.0;  // spheres near the silhouette: the chord of the sphere grown by delta
  double graze_t = 0.0;   // triangles: kGrazeT S K / (|cos| |d|), the rounding of t at grazing angles
  glm::vec3 vertex[3]{};  // triangles: the vertices; spheres: center in [0], radius in [1].x

  bool reachable() const { return distance <= delta; }
  double t_tolerance(double dir_length) const;  // kRelT |t| + max(kWorld S / |d|, graze_t) at this t
};

// The scene's shapes by geometry id, and the largest coordinate magnitude (which bounds S over the scene).
class ShapeIndex {
 public:
  explicit ShapeIndex(const SceneGeometry& geometry);
  const TriangleMesh* mesh(std::uint32_t geom_id) const { return geom_id < meshes_.size() ? meshes_[geom_id] : nullptr; }
  const Sphere* sphere(std::uint32_t geom_id) const { return geom_id < spheres_.size() ? spheres_[geom_id] : nullptr; }
  double max_coordinate() const { return max_coordinate_; }

 private:
  std::vector<const TriangleMesh*> meshes_;
  std::vector<const Sphere*> spheres_;
  double max_coordinate_ = 0.0;
};

// Every primitive that the ray's line reaches (within its delta) for a t within tolerance of [tmin, tmax],
// evaluated; hits are decided exactly.
std::vector<Candidate> near_candidates(const ExactBackend& exact, const ShapeIndex& shapes, const Ray& ray);

// One primitive, evaluated the same way (whether or not the ray reaches it). `ok` is false for an unknown
// (geom_id, prim_id).
Candidate evaluate_primitive(const ShapeIndex& shapes, const Ray& ray, PrimitiveRef ref, bool& ok);

}  // namespace twinray::arbiter
