#include "harness/grade/interval_ends.h"

#include "core/sampling/rng.h"

#include <fmt/core.h>

#include <bit>
#include <cmath>

namespace twinray::grade {

namespace {

// A triangle whose crossing along its plane's axis every float test computes exactly (interval_ends.h): its
// plane's axis, or -1.
int exact_crossing_axis(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2) {
  for (const glm::vec3& p : {p0, p1, p2})
    for (int k = 0; k < 3; ++k)
      if (!(std::fabs(p[k]) <= 1024.0f) || p[k] != std::trunc(p[k])) return -1;
  for (int k = 0; k < 3; ++k) {
    if (p0[k] != p1[k] || p0[k] != p2[k]) continue;
    const int x = (k + 1) % 3, y = (k + 2) % 3;
    // Twice the area in the plane: an integer below 2^22, exact in double.
    const double twice_area = std::fabs(double(p1[x] - p0[x]) * double(p2[y] - p0[y]) -
                                        double(p1[y] - p0[y]) * double(p2[x] - p0[x]));
    if (twice_area == 0.0) return -1;
    return std::has_single_bit(static_cast<std::uint64_t>(twice_area)) ? k : -1;
  }
  return -1;
}

}  // namespace

std::vector<IntervalEndRay> interval_end_rays(const Scene& scene, std::size_t count, std::uint64_t seed) {
  struct Target {
    const TriangleMesh* mesh;
    std::uint32_t prim;
    int axis;
  };
  std::vector<Target> targets;
  for (const TriangleMesh& mesh : scene.geometry.meshes)
    for (std::size_t i = 0; i < mesh.indices.size(); ++i) {
      const glm::uvec3 tri = mesh.indices[i];
      const int axis = exact_crossing_axis(mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]);
      if (axis >= 0) targets.push_back({&mesh, static_cast<std::uint32_t>(i), axis});
    }
  std::vector<IntervalEndRay> out;
  if (targets.empty()) return out;
  Rng rng = Rng::keyed(seed, 0x1e9d, 7);
  out.reserve(count);
  for (std::size_t n = 0; n < count; ++n) {
    const Target& target = targets[rng.next_below(static_cast<std::uint32_t>(targets.size()))];
    const glm::uvec3 tri = target.mesh->indices[target.prim];
    const glm::vec3 p0 = target.mesh->positions[tri[0]], p1 = target.mesh->positions[tri[1]],
                    p2 = target.mesh->positions[tri[2]];
    // Multiples of 1/4 below 2^11: exact.
    const glm::vec3 at = 0.5f * p0 + 0.25f * p1 + 0.25f * p2;
    const float side = rng.next_below(2) == 0 ? 1.0f : -1.0f;
    const float distance = std::ldexp(1.0f, static_cast<int>(rng.next_below(3)) - 1);  // 1/2, 1 or 2
    glm::vec3 dir(0.0f);
    dir[target.axis] = side;
    IntervalEndRay r;
    r.ray.org = at - distance * dir;
    r.ray.dir = dir;
    r.geom_id = target.mesh->geom_id;
    r.prim_id = target.prim;
    r.t = distance;
    switch (rng.next_below(4)) {
      case 0: r.ray.tmin = 0.0f, r.ray.tmax = distance, r.counts = true; break;                  // ends at it
      case 1: r.ray.tmin = distance, r.ray.tmax = 2.0f * distance, r.counts = true; break;      // starts at it
      case 2: r.ray.tmin = 0.0f, r.ray.tmax = std::nextafter(distance, 0.0f); break;            // ends one float short
      default: r.ray.tmin = std::nextafter(distance, INFINITY), r.ray.tmax = 2.0f * distance;  // starts one float past
    }
    out.push_back(r);
  }
  return out;
}

std::vector<IntervalEndRay> unambiguous_ends(const arbiter::Arbiter& exact, std::vector<IntervalEndRay> ends) {
  std::erase_if(ends, [&](const IntervalEndRay& e) {
    const Hit h = exact.exact_closest(e.ray);
    if (!e.counts) return h.found();
    return !(h.geom_id == e.geom_id && h.prim_id == e.prim_id && h.t == e.t);
  });
  return ends;
}

EndJudgement judge_ends(std::span<const IntervalEndRay> ends, const Answers& mine) {
  EndJudgement j;
  for (std::size_t i = 0; i < ends.size(); ++i) {
    const IntervalEndRay& e = ends[i];
    const Hit& h = mine.hits[i];
    const bool closest_right = e.counts ? h.geom_id == e.geom_id && h.prim_id == e.prim_id && h.t >= e.ray.tmin &&
                                              h.t <= e.ray.tmax
                                        : !h.found();
    const bool any_right = (mine.occluded[i] != 0) == e.counts;
    j.wrong += (closest_right ? 0 : 1) + (any_right ? 0 : 1);
    if ((!closest_right || !any_right) && !j.first) {
      j.first = i;
      j.first_any_hit = closest_right;
      const std::string where =
          e.counts ? fmt::format("the crossing of geom {} prim {} at t {} is the interval's {} end (closed) and counts",
                                 e.geom_id, e.prim_id, e.t, e.ray.tmin == e.t ? "lower" : "upper")
                   : fmt::format("the crossing of geom {} prim {} at t {} lies one float outside [{}, {}] and nothing "
                                 "else is in it",
                                 e.geom_id, e.prim_id, e.t, e.ray.tmin, e.ray.tmax);
      j.first_description =
          closest_right ? fmt::format("plugin says {}occluded; {}", mine.occluded[i] ? "" : "not ", where)
                        : fmt::format("plugin {}; {}", h.found() ? "hits " + describe_hit(h) : std::string("misses"),
                                      where);
    }
  }
  return j;
}

}  // namespace twinray::grade
