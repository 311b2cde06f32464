// bvh8's any-hit leaves decide a candidate by the sign of its t first (refine_in_interval_v with kBySign,
// triangle_refine.h): certainly_behind drops a crossing whose exact t is at most -2^-126, certainly_inside
// accepts one strictly inside the interval, the quotient decides the rest; its closest-hit leaves drop a
// crossing certainly_behind before the quotient (refine_t_kept_v with kBehindFirst). And the block edge test sends a lane
// whose product u v w is 0 or NaN (or underflows) to the scalar test (triangle_block.h). Neither may change an
// answer: checked here against the correctly rounded t on adversarial crossings (origins exactly on the
// triangle, on its edges and vertices, a few ulps off it either side, Wächter-Binder offsets, grazing and
// parallel directions, slivers, tiny and huge scales), with and without flush-to-zero, and on whole scenes
// whose edge functions underflow.

#include "backends/brute/brute_backend.h"
#include "backends/bvh/bvh_backend.h"
#include "backends/simd/isa.h"
#include "backends/wide/wide_backend.h"
#include "core/geometry/ray_offset.h"
#include "core/intersect/triangle_refine.h"
#include "core/sampling/rng.h"
#include "core/scene/procedural.h"
#include "core/util/fp_mode.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace twinray {
namespace {

using refine_detail::Crossing;
using refine_detail::RefineRay;

// A float point of the triangle at barycentrics (b1, b2) (on an edge or a vertex when one is 0 or 1).
glm::vec3 point_on(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2, double b1, double b2) {
  const glm::dvec3 q = glm::dvec3(p0) * (1.0 - b1 - b2) + glm::dvec3(p1) * b1 + glm::dvec3(p2) * b2;
  return glm::vec3(q);
}

glm::vec3 step_ulps(const glm::vec3& p, const glm::vec3& toward, int ulps) {
  glm::vec3 q = p;
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < ulps; ++k)
      q[a] = std::nextafter(q[a], toward[a] > 0.0f ? std::numeric_limits<float>::infinity()
                                                  : -std::numeric_limits<float>::infinity());
  return q;
}

struct BySignCounts {
  int crossings = 0, behind = 0, agreeing = 0;
};

// Every crossing of one ray with one triangle: the predicate's promise and the whole membership test.
void check_crossing(const glm::vec3& o, const glm::vec3& d, const glm::vec3& p0, const glm::vec3& p1,
                    const glm::vec3& p2, BySignCounts& counts) {
  if (d == glm::vec3(0.0f)) return;
  RefineRay ray;
  refine_detail::set_ray(ray, o, d);
  constexpr float kMax = std::numeric_limits<float>::max();
  Crossing c;
  if (refine_detail::crossing_sums(ray, refine_detail::load(p0), refine_detail::load(p1), refine_detail::load(p2), c)) {
    ++counts.crossings;
    if (refine_detail::certainly_behind(c)) {
      ++counts.behind;
      float t = 0.0f;
      // The correctly rounded t of the crossing (the exact path when the bound cannot tell).
      if (refine_detail::refine_t(ray, p0, p1, p2, -kMax, kMax, t)) {
        EXPECT_LE(t, -0x1p-126f) << "t " << t;
      }
    }
  }
  // The whole test against the correctly rounded t, on intervals with ends at 0, at subnormals, at the
  // smallest normal float, around the crossing and unbounded.
  const float inf = std::numeric_limits<float>::infinity();
  const float intervals[][2] = {{0.0f, inf},       {-0.0f, 1.0f},    {0x1p-140f, inf}, {0x1p-126f, inf},
                                {1e-6f, 1.0f},     {0.0f, 0x1p-140f}, {0.0f, 1e-6f},   {0.5f, 2.0f},
                                {0.0f, kMax}};
  for (const auto& iv : intervals) {
    float t = 0.0f;
    const bool expected = refine_detail::refine_t(ray, p0, p1, p2, iv[0], iv[1], t);
    const bool by_sign =
        refine_detail::refine_in_interval</*kDivisionFreeFirst=*/false, /*kBySign=*/true>(ray, p0, p1, p2, iv[0], iv[1]);
    EXPECT_EQ(by_sign, expected) << "interval [" << iv[0] << ", " << iv[1] << "]";
    counts.agreeing += by_sign == expected ? 1 : 0;
    // Closest hit drops a crossing certainly behind before the quotient (kBehindFirst): the same t, or none.
    if (!(iv[0] >= 0.0f)) continue;
    Crossing kept;
    float t_behind_first = 0.0f;
    const bool found = refine_detail::refine_t</*kBehindFirst=*/true>(
        ray, p0, p1, p2, iv[0], iv[1], t_behind_first, kept,
        [&](float& te, float& ue, float& ve) { return refine_detail::exact_crossing_of(ray, p0, p1, p2, te, ue, ve); });
    EXPECT_EQ(found, expected) << "closest, interval [" << iv[0] << ", " << iv[1] << "]";
    if (found && expected) {
      EXPECT_EQ(t_behind_first, t);
    }
  }
}

void run_adversarial_crossings(BySignCounts& counts) {
  Rng rng(2027, 11);
  const auto coord = [&] { return 2.0f * rng.next_float() - 1.0f; };
  for (int tri = 0; tri < 60; ++tri) {
    // Scales from 2^-40 to 2^40, translated far from the origin half of the time; every fifth a sliver.
    const float scale = std::ldexp(1.0f, static_cast<int>(rng.next_below(9)) * 10 - 40);
    const glm::vec3 shift = rng.next_below(2) ? glm::vec3(coord(), coord(), coord()) * (scale * 64.0f) : glm::vec3(0.0f);
    const glm::vec3 p0 = shift + glm::vec3(coord(), coord(), coord()) * scale;
    const glm::vec3 p1 = shift + glm::vec3(coord(), coord(), coord()) * scale;
    glm::vec3 p2 = shift + glm::vec3(coord(), coord(), coord()) * scale;
    if (tri % 5 == 0) p2 = point_on(p0, p1, p2, 0.5, 1e-4);
    const glm::dvec3 nd = glm::cross(glm::dvec3(p1) - glm::dvec3(p0), glm::dvec3(p2) - glm::dvec3(p0));
    if (glm::length(nd) == 0.0) continue;
    const glm::vec3 n = glm::vec3(glm::normalize(nd));
    const double bary[][2] = {{1.0 / 3.0, 1.0 / 3.0}, {0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}, {0.5, 0.0},
                              {0.0, 0.5},             {0.5, 0.5}, {rng.next_double() * 0.5, rng.next_double() * 0.5}};
    for (const auto& b : bary) {
      const glm::vec3 p = point_on(p0, p1, p2, b[0], b[1]);
      for (const float side : {1.0f, -1.0f}) {
        const glm::vec3 toward = side * n;
        // The origin exactly at the point, a few ulps off either side, and at the renderer's offset.
        const glm::vec3 origins[] = {p, step_ulps(p, toward, 1), step_ulps(p, toward, 4), step_ulps(p, -toward, 2),
                                     offset_ray_origin(p, toward)};
        for (const glm::vec3& o : origins) {
          // Directions away from the plane and into it, grazing ones, one in the plane, and long ones (t is
          // not a distance: at 2^90 the crossing of an origin a few ulps off a small triangle is a t that
          // rounds to -0 or to a subnormal, which counts as t = 0 under flush-to-zero).
          glm::vec3 tangent = glm::vec3(glm::normalize(glm::cross(glm::dvec3(n), glm::dvec3(coord(), coord(), coord()))));
          const glm::vec3 dirs[] = {toward, -toward, glm::normalize(toward + tangent), glm::normalize(-toward + tangent),
                                    tangent + 1e-3f * toward, tangent - 1e-6f * toward, tangent,
                                    (toward + 0.3f * tangent) * 4096.0f, toward * 0x1p90f,
                                    (tangent - toward) * 0x1p90f};
          for (const glm::vec3& d : dirs) check_crossing(o, d, p0, p1, p2, counts);
        }
      }
    }
  }
}

TEST(AnyHitBySign, CertainlyBehindNeverDropsAHitAndTheTestMatchesTheRoundedT) {
  BySignCounts plain;
  run_adversarial_crossings(plain);
  BySignCounts flushed;
  {
    const ScopedFlushDenormals ftz;
    run_adversarial_crossings(flushed);
  }
  // The predicate must actually fire (offset origins behind their direction), and not everywhere.
  for (const BySignCounts* c : {&plain, &flushed}) {
    EXPECT_GT(c->behind, c->crossings / 10);
    EXPECT_LT(c->behind, c->crossings);
    EXPECT_GT(c->agreeing, 50000);
  }
}

// A soup at 2^-45: the edge functions are about 2^-90 and their product underflows, so the block test sends
// every lane the signs would have decided to the scalar test. bvh8 (every instruction set) and bvh must still
// answer exactly as brute, closest and any hit, with and without flush-to-zero.
TEST(AnyHitBySign, UnderflowingEdgeProductsTakeTheScalarTestAlike) {
  SceneGeometry g = random_triangle_soup(400, 5);
  for (glm::vec3& p : g.meshes[0].positions)
    for (int a = 0; a < 3; ++a) p[a] = std::ldexp(p[a], -45);
  const Bounds3 box = g.bounds();
  std::vector<std::unique_ptr<Backend>> backends;
  std::vector<std::string> labels;
  for (const Isa isa : runnable_isas()) {
    backends.push_back(make_wide_backend({}, isa));
    labels.push_back("bvh8 " + std::string(to_string(isa)));
    backends.push_back(make_bvh_backend({}, isa));
    labels.push_back("bvh " + std::string(to_string(isa)));
  }
  auto brute = make_brute_backend();
  brute->build(g);
  for (auto& b : backends) b->build(g);
  for (const bool ftz : {false, true}) {
    std::unique_ptr<ScopedFlushDenormals> mode;
    if (ftz) mode = std::make_unique<ScopedFlushDenormals>();
    Rng rng(99, 1);
    int hits = 0;
    for (int i = 0; i < 600; ++i) {
      const glm::vec3 e = box.hi - box.lo;
      const auto in_box = [&] {
        return box.lo + e * glm::vec3(rng.next_float(), rng.next_float(), rng.next_float()) * 1.4f - e * 0.2f;
      };
      Ray r;
      r.org = in_box();
      r.dir = in_box() - r.org;
      if (r.dir == glm::vec3(0.0f)) continue;
      r.tmax = rng.next_below(2) ? std::numeric_limits<float>::infinity() : 0.5f;
      Hit expected;
      const bool found = brute->intersect(r, expected);
      const bool occluded = brute->occluded(r);
      hits += found ? 1 : 0;
      for (std::size_t k = 0; k < backends.size(); ++k) {
        Hit h;
        EXPECT_EQ(backends[k]->intersect(r, h), found) << labels[k];
        EXPECT_EQ(h.prim_id, expected.prim_id) << labels[k];
        EXPECT_EQ(h.t, expected.t) << labels[k];
        EXPECT_EQ(h.u, expected.u) << labels[k];
        EXPECT_EQ(h.v, expected.v) << labels[k];
        EXPECT_EQ(backends[k]->occluded(r), occluded) << labels[k];
      }
    }
    EXPECT_GT(hits, 100) << "ftz " << ftz;
  }
}

}  // namespace
}  // namespace twinray
