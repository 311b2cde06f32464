#pragma once
// Helpers the stress families share: building a backend on a case's own geometry, deciding what a backend
// claims, counting surface crossings along a ray, and small exactly-representable meshes.

#include "harness/stress/stress_case.h"
#include "core/backend/backend.h"
#include "core/geometry/scene_geometry.h"

#include <glm/vec3.hpp>

#include <cstddef>
#include <memory>
#include <string>

namespace twinray::stress {

// make_backend + build. The geometry must outlive the backend (Embree shares its buffers).
std::unique_ptr<Backend> build_backend(const std::string& name, const SceneGeometry& geometry);

// Embree's fast mode is reported, never required: it is the speed reference, not a robustness claim.
bool is_fast_mode(const std::string& backend);

// An outcome's `required` for a backend whose traits say `claimed`: false for embree-fast and for backends
// that do not claim the property, with a note saying which.
void set_requirement(Outcome& outcome, const std::string& backend, bool claimed, std::string_view property);

// Ray and sample counts scaled by the effort, never below `minimum`.
std::size_t scaled(std::size_t count, const StressOptions& options, std::size_t minimum = 16);

// How many surfaces the ray crosses in [tmin, tmax]: closest hits, restarting just past each one
// (tmin = next float above t). Two triangles meeting at the crossing point at the same t count once (the
// closest-hit query cannot tell them apart), which is what "crossing" means. Stops at `limit`.
int count_crossings(const Backend& backend, Ray ray, int limit = 16);

// Crossings of a ray through a surface, split into distinct ones and same-point duplicates: a hit whose t
// is within kSamePointUlps ulps of the previous hit's is the same surface point reported by a second
// triangle (two faces meeting at an edge the ray passes through).
inline constexpr int kSamePointUlps = 4;
struct Crossings {
  int distinct = 0;
  int same_point_duplicates = 0;
};
Crossings classify_crossings(const Backend& backend, Ray ray, int limit = 16);

// A closed axis-aligned box [lo, hi]^3 (integer corners), each face split into unit squares, two
// triangles each, counter-clockwise seen from outside. Vertices on shared edges are bit-identical
// (integers), so the mesh is closed even though faces do not share vertex indices.
TriangleMesh integer_box_mesh(int lo, int hi, std::uint32_t geom_id = 0);

// 0 for a, (b - a) / max(|a|, |b|) otherwise; for comparing t values across scales.
double relative_difference(double a, double b);

// The result of a set of checks: counts of what failed, what passed, in one place.
struct Tally {
  std::size_t rays = 0;
  std::size_t failures = 0;
  void check(bool ok) {
    ++rays;
    failures += ok ? 0 : 1;
  }
};

}  // namespace twinray::stress
