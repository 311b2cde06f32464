#pragma once
// Comparing two backends' answers to the same rays, and explaining every disagreement.
//
// Two closest hits are *identical* when both miss, or both hit the same (geom_id, prim_id) at parameters
// that agree within the t tolerance below. Every other outcome is a mismatch, classified as
//   edge     the hit lies on a boundary where two correct intersectors may legitimately differ: within the
//            world-space tolerance of a triangle edge or vertex, on a sphere's silhouette (grazing), or at the
//            end of the ray's interval [tmin, tmax];
//   tie      not an edge case; both hit, different primitives, at parameters equal within the t tolerance (coplanar or
//            duplicated geometry; only backends with honours_ties resolve these identically);
//   genuine  anything else: a real bug in one of the backends.
//
// Tolerances (why these numbers):
//  - t: |ta - tb| <= kRelT * max(ta, tb) + kAbsWorld * (D + |org|) / |dir|. kRelT = 1e-4 allows a few
//    hundred float ulps between two different float triangle algorithms (Woop's shear vs Embree's Pluecker
//    form); the second term is the absolute position error of float coordinates of magnitude (D + |org|),
//    with D the scene's bounding-box diagonal.
//  - edge: the hit point is within kAbsWorld * (D + |p|) of an edge, measured in world units as
//    barycentric * altitude, so the margin does not depend on the triangle's size. kAbsWorld = 1e-5 is
//    about 100 ulps of the coordinates, far above the float error of either algorithm and far below the
//    size of any region a traversal bug would lose.
//  - grazing sphere hits: |cos(normal, dir)| < kGrazingCos = 1e-3, where the root is ill-conditioned.

#include "core/backend/backend.h"
#include "core/scene/scene.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace twinray::crosscheck {

inline constexpr double kRelT = 1e-4;
inline constexpr double kAbsWorld = 1e-5;
inline constexpr double kGrazingCos = 1e-3;

enum class MismatchClass { Edge, Tie, Genuine };
std::string_view to_string(MismatchClass c);

struct Mismatch {
  std::size_t ray_index = 0;
  MismatchClass kind = MismatchClass::Genuine;
  bool occlusion = false;  // an any-hit disagreement rather than a closest-hit one
  Hit a, b;
  bool occluded_a = false, occluded_b = false;
};

struct PairComparison {
  std::string baseline;  // backend a
  std::string other;     // backend b
  std::size_t rays = 0;
  std::size_t hits_a = 0, hits_b = 0;
  std::size_t identical = 0;
  std::size_t edge = 0, tie = 0, genuine = 0;
  double max_rel_t_diff = 0.0;  // over rays where both hit the same primitive
  // Any-hit answers.
  std::size_t occlusion_agree = 0;
  std::size_t occlusion_edge = 0, occlusion_genuine = 0;
  std::vector<Mismatch> examples;  // the first genuine mismatches, for diagnosis
  // Every ray whose closest hits are not identical (edge, tie or genuine), and every ray whose any-hit answers
  // differ, in ray order: what the arbiter rules on (harness/arbiter/arbiter.h).
  std::vector<std::size_t> closest_disputes, occlusion_disputes;

  double identical_fraction() const { return rays ? static_cast<double>(identical) / static_cast<double>(rays) : 1.0; }
};

// Looks up primitives by (geom_id, prim_id) to measure distances to edges.
class GeometryIndex {
 public:
  explicit GeometryIndex(const SceneGeometry& geometry);
  const TriangleMesh* mesh(std::uint32_t geom_id) const;
  const Sphere* sphere(std::uint32_t geom_id) const;
  float diagonal() const { return diagonal_; }

 private:
  const SceneGeometry& geometry_;
  std::vector<std::int64_t> mesh_of_geom_;    // -1 when not a mesh
  std::vector<std::int64_t> sphere_of_geom_;  // -1 when not a sphere
  float diagonal_ = 0.0f;
};

// True when the hit sits on a boundary where correct intersectors may differ (see the header comment).
bool hit_is_ambiguous(const GeometryIndex& index, const Ray& ray, const Hit& hit);
bool t_agrees(const GeometryIndex& index, const Ray& ray, float ta, float tb);

// One ray's two answers, classified as compare() counts them: the closest hits (identical, edge, tie or
// genuine) and the any-hit flags (agree, edge or genuine).
enum class OcclusionClass { Agree, Edge, Genuine };
struct RayComparison {
  bool identical = false;  // closest hits identical
  MismatchClass kind = MismatchClass::Genuine;  // when not identical
  OcclusionClass occlusion = OcclusionClass::Agree;
  std::optional<double> rel_t_diff;  // both hit the same primitive
};
RayComparison compare_ray(const GeometryIndex& index, const Ray& ray, const Hit& a, const Hit& b, bool occluded_a,
                          bool occluded_b);

PairComparison compare(const GeometryIndex& index, std::span<const Ray> rays, std::span<const Hit> a,
                       std::span<const Hit> b, std::span<const std::uint8_t> occluded_a,
                       std::span<const std::uint8_t> occluded_b, std::size_t max_examples = 5);

}  // namespace twinray::crosscheck
