// The interval test of every triangle backend uses the correctly rounded t, at the ends too: with tmax (or
// tmin) set to a hit's rounded t or to the floats next to it, closest-hit and any-hit queries of bvh, bvh8,
// brute and exact agree with what that t says, on grazing rays at thin triangles (whose t interval in double
// is widest, so the ends are decided by certification or the exact path) as on ordinary ones; and a closest
// hit's u, v and normal are those of the exact crossing and of the plain formula.

#include "backends/brute/brute_backend.h"
#include "backends/bvh/bvh_backend.h"
#include "backends/exact/exact_backend.h"
#include "backends/simd/isa.h"
#include "backends/wide/wide_backend.h"
#include "core/exact/exact_number.h"
#include "core/exact/exact_triangle.h"
#include "core/intersect/triangle_watertight.h"
#include "core/sampling/rng.h"
#include "ray_test_util.h"
#include "sliver_test_util.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace twinray {
namespace {

using test::same_bits;

using test::to_float;

using TriangleSet = test::SliverSet;

// 48 triangles of aspect 1 to 1e4 in random orientations, each shot through an interior point from 0.05 to 90
// degrees above its plane (grazing ones half of the time), from either side.
TriangleSet triangle_set(std::uint64_t seed) {
  test::SliverSetParams params;
  params.triangles = 48;
  params.rays_per_triangle = 16;
  params.log10_aspect_min = 0.0;
  params.log10_aspect_span = 4.0;
  params.base_extent = 3.0;
  params.degrees = [](Rng& rng) {
    return rng.next_below(2) ? 0.05 * std::pow(20.0, static_cast<double>(rng.next_float()))
                             : 90.0 * static_cast<double>(rng.next_float()) + 0.01;
  };
  params.distance_min = 0.1;
  params.distance_span = 4.0;
  params.direction_scale = [](Rng& rng) { return 0.25 + 2.0 * rng.next_float(); };  // t is not a distance
  return test::sliver_set(seed, params);
}

// The normal as triangle_geometric_normal has always computed it: the cross product in double, normalized.
glm::vec3 plain_normal(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2) {
  const glm::dvec3 e1 = glm::dvec3(p1) - glm::dvec3(p0), e2 = glm::dvec3(p2) - glm::dvec3(p0);
  const double nx = e1.y * e2.z - e1.z * e2.y, ny = e1.z * e2.x - e1.x * e2.z, nz = e1.x * e2.y - e1.y * e2.x;
  const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
  return to_float(glm::dvec3(nx / len, ny / len, nz / len));
}

TEST(RefinedInterval, EndsAtTheRoundedTDecideEveryBackendAlike) {
  const TriangleSet set = triangle_set(11);
  std::vector<std::unique_ptr<Backend>> backends;
  std::vector<std::string> labels;
  backends.push_back(make_brute_backend());
  labels.emplace_back("brute");
  // The kernels of every instruction set (the refinement's vectors are two SSE2 operations or one AVX one).
  for (const Isa isa : runnable_isas()) {
    backends.push_back(make_bvh_backend({}, isa));
    labels.push_back("bvh " + std::string(to_string(isa)));
    backends.push_back(make_wide_backend({}, isa));
    labels.push_back("bvh8 " + std::string(to_string(isa)));
  }
  backends.push_back(make_exact_backend());
  labels.emplace_back("exact");
  for (const auto& b : backends) b->build(set.geometry);
  const TriangleMesh& mesh = set.geometry.meshes[0];
  std::size_t hits = 0, checked = 0;
  for (const Ray& ray : set.rays) {
    Hit reference;
    if (!backends[0]->intersect(ray, reference)) continue;
    const glm::uvec3& tri = mesh.indices[reference.prim_id];
    const glm::vec3 p0 = mesh.positions[tri.x], p1 = mesh.positions[tri.y], p2 = mesh.positions[tri.z];
    const exact::TriangleCrossing c = exact::intersect_triangle_exact(
        {exact::to_double_exact(ray.org), exact::to_double_exact(ray.dir), exact::to_double_exact(p0),
         exact::to_double_exact(p1), exact::to_double_exact(p2)});
    // Where the float edge decision and the exact one differ (at an edge), the exact backend answers
    // otherwise by design: the other backends are still compared with each other.
    const bool exact_agrees = c.hit;
    ++hits;
    const float t = reference.t;
    ASSERT_TRUE(same_bits(t, c.t)) << t << " exact " << c.t;
    EXPECT_TRUE(same_bits(reference.u, c.u) && same_bits(reference.v, c.v));
    const glm::vec3 n = plain_normal(p0, p1, p2);
    EXPECT_TRUE(same_bits(reference.ng.x, n.x) && same_bits(reference.ng.y, n.y) && same_bits(reference.ng.z, n.z));
    const float below = std::nextafter(t, 0.0f), above = std::nextafter(t, std::numeric_limits<float>::infinity());
    // tmax at the rounded t and just below it: the hit counts, then nothing does (it is the closest).
    // tmin at the rounded t: the same hit; just above it: only farther ones.
    struct Case {
      float tmin, tmax;
      bool same_hit;
    };
    for (const Case& k : {Case{0.0f, t, true}, Case{0.0f, below, false}, Case{t, ray.tmax, true},
                          Case{above, ray.tmax, false}}) {
      Ray r = ray;
      r.tmin = k.tmin;
      r.tmax = k.tmax;
      for (std::size_t i = 0; i < backends.size(); ++i) {
        const Backend* b = backends[i].get();
        if (b->name() == "exact" && !exact_agrees) continue;
        SCOPED_TRACE(labels[i]);
        Hit h;
        const bool found = b->intersect(r, h);
        const bool occluded = b->occluded(r);
        ++checked;
        if (k.same_hit) {
          ASSERT_TRUE(found) << b->name();
          EXPECT_EQ(h.prim_id, reference.prim_id) << b->name();
          EXPECT_TRUE(same_bits(h.t, t) && same_bits(h.u, reference.u) && same_bits(h.v, reference.v))
              << b->name() << " t " << h.t << " expected " << t;
          EXPECT_TRUE(same_bits(h.ng.x, reference.ng.x) && same_bits(h.ng.y, reference.ng.y) &&
                      same_bits(h.ng.z, reference.ng.z))
              << b->name();
        } else if (k.tmin == 0.0f) {
          EXPECT_FALSE(found) << b->name() << " found t " << h.t << " with tmax just below " << t;
        } else if (found) {
          EXPECT_GT(h.t, t) << b->name();
        }
        EXPECT_EQ(occluded, found) << b->name() << " tmin " << r.tmin << " tmax " << r.tmax;
      }
    }
  }
  EXPECT_GT(hits, set.rays.size() / 2);
  EXPECT_GT(checked, hits * 4 * backends.size() - hits * 4);
}

// A crossing at t = 1 + 2^-24 exactly (a rounding tie, to 1): it lies inside [0, 1] by its rounded t although
// its exact t exceeds 1, and outside [1 + 2^-23, 2]. The any-hit test must decide by the rounded t too, which
// here only the exact path knows.
TEST(RefinedInterval, AnyHitUsesTheRoundedTAtATie) {
  const glm::vec3 org(0.25f, 0.25f, 1.0f), dir(0.0f, 0.0f, -1.0f);
  const glm::vec3 p0(0.0f, 0.0f, -0x1p-24f), p1(1.0f, 0.0f, -0x1p-24f), p2(0.0f, 1.0f, -0x1p-24f);
  const TriangleRay ray = make_triangle_ray(org, dir);
  EXPECT_TRUE(intersect_triangle_any(ray, p0, p1, p2, 0.0f, 1.0f));
  EXPECT_FALSE(intersect_triangle_any(ray, p0, p1, p2, 0.0f, std::nextafter(1.0f, 0.0f)));
  EXPECT_TRUE(intersect_triangle_any(ray, p0, p1, p2, 1.0f, 2.0f));
  EXPECT_FALSE(intersect_triangle_any(ray, p0, p1, p2, 1.0f + 0x1p-23f, 2.0f));
  // Just past the tie (t rounds up to 1 + 2^-23): outside [0, 1].
  const glm::vec3 q0(0.0f, 0.0f, -0x1.000002p-24f), q1(1.0f, 0.0f, -0x1.000002p-24f), q2(0.0f, 1.0f, -0x1.000002p-24f);
  EXPECT_FALSE(intersect_triangle_any(ray, q0, q1, q2, 0.0f, 1.0f));
  EXPECT_TRUE(intersect_triangle_any(ray, q0, q1, q2, 0.0f, 1.0f + 0x1p-23f));
  // Far inside or outside the interval the bound decides without exact work.
  const std::uint64_t before = refine_detail::exact_fallbacks.load();
  EXPECT_TRUE(intersect_triangle_any(ray, p0, p1, p2, 0.5f, 1.5f));
  EXPECT_FALSE(intersect_triangle_any(ray, p0, p1, p2, 1.5f, 2.5f));
  EXPECT_FALSE(intersect_triangle_any(ray, p0, p1, p2, 0.0f, 0.5f));
  EXPECT_EQ(refine_detail::exact_fallbacks.load(), before);
}

// A barycentric whose interval lies at or below 0 is reported as +0, as the exact path clamps it (not -0):
// rays through an edge or a vertex of a triangle hit it with u or v exactly 0 by the same bits in every
// backend.
TEST(RefinedInterval, ClampedBarycentricsArePositiveZero) {
  SceneGeometry geometry;
  TriangleMesh mesh;
  mesh.positions = {{0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}};
  mesh.indices = {{0, 1, 2}};
  ensure_vertex_padding(mesh.positions);
  geometry.meshes.push_back(std::move(mesh));
  std::vector<std::unique_ptr<Backend>> backends;
  backends.push_back(make_brute_backend());
  backends.push_back(make_bvh_backend());
  backends.push_back(make_exact_backend());
  for (const auto& b : backends) b->build(geometry);
  // Through the vertices and edges, slanted every way, so that the fill rule gives some of them to the
  // triangle. Through p1 the vector from p0 to the crossing is e1 itself and v's numerator -e1.(e1 x d)
  // cancels to exactly -0: the clamp must still give +0.
  std::size_t zeros = 0;
  for (const glm::vec3 target : {glm::vec3(0.0f, 0.0f, 0.0f), glm::vec3(1.0f, 0.0f, 0.0f), glm::vec3(0.0f, 1.0f, 0.0f),
                                 glm::vec3(0.375f, 0.0f, 0.0f), glm::vec3(0.0f, 0.625f, 0.0f)}) {
    for (const glm::vec3 dir : {glm::vec3(0.25f, 0.5f, -1.0f), glm::vec3(-0.25f, -0.5f, -1.0f),
                                glm::vec3(0.25f, -0.5f, -1.0f), glm::vec3(-0.25f, 0.5f, -1.0f)}) {
      Ray ray;
      ray.org = target - dir;
      ray.dir = dir;
      for (const auto& b : backends) {
        Hit h;
        if (!b->intersect(ray, h)) continue;
        EXPECT_FALSE(std::signbit(h.u) || std::signbit(h.v)) << b->name() << " u " << h.u << " v " << h.v;
        zeros += (h.u == 0.0f || h.v == 0.0f) ? 1 : 0;
      }
    }
  }
  EXPECT_GT(zeros, 0u);
  // The refinement itself, on crossings exactly at a vertex (coordinates on a grid of 1/64, so that the
  // origin target - d is exact): t is exact and every 0 it reports is +0. (A -0 from an exactly cancelling
  // numerator is what ExactBackend.AgreesWithBruteExceptWhereTheFloatEdgeTestDiffers caught.)
  Rng rng(5, 0);
  const auto grid = [&rng] { return static_cast<double>(static_cast<int>(rng.next_below(257)) - 128) / 64.0; };
  std::size_t refined_zeros = 0;
  for (int k = 0; k < 3000; ++k) {
    const glm::dvec3 p[3] = {{grid(), grid(), grid()}, {grid(), grid(), grid()}, {grid(), grid(), grid()}};
    const glm::dvec3 d(grid(), grid(), grid());
    const glm::dvec3 target = p[rng.next_below(3)];
    float t = 0.0f, u = 0.0f, w = 0.0f;
    if (!refine_triangle_hit(target - d, d, p[0], p[1], p[2], 0.0f, 2.0f, t, u, w)) continue;
    EXPECT_EQ(t, 1.0f);
    EXPECT_FALSE(std::signbit(u) || std::signbit(w)) << "u " << u << " v " << w;
    refined_zeros += (u == 0.0f ? 1 : 0) + (w == 0.0f ? 1 : 0);
  }
  EXPECT_GT(refined_zeros, 1000u);
}

}  // namespace
}  // namespace twinray
