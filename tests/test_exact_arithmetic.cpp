// Exact arithmetic (core/exact/): conversions that ignore denormals-are-zero, correct rounding of quotients to
// float across the subnormal range and at overflow, exact ray-triangle and ray-sphere answers with analytic
// values, the fill rule on shared edges and vertices, and the refinement's fallback to the exact path.

#include "core/exact/exact_integer.h"
#include "core/exact/exact_number.h"
#include "core/exact/exact_sphere.h"
#include "core/exact/exact_triangle.h"
#include "core/intersect/triangle_refine.h"
#include "core/intersect/triangle_watertight.h"
#include "core/scene/procedural.h"
#include "core/util/fp_mode.h"
#include "ray_test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace twinray {
namespace {

using exact::round_quotient_to_float;
using test::same_bits;

mpz_class pow2(unsigned k) {
  mpz_class z = 1;
  z <<= k;
  return z;
}

exact::RayTriangle ray_triangle(glm::vec3 o, glm::vec3 d, glm::vec3 p0, glm::vec3 p1, glm::vec3 p2) {
  return {exact::to_double_exact(o), exact::to_double_exact(d), exact::to_double_exact(p0), exact::to_double_exact(p1),
          exact::to_double_exact(p2)};
}

TEST(ExactNumber, FloatsAreReadFromTheirBitsEvenUnderDenormalsAreZero) {
  const ScopedFlushDenormals daz;
  volatile float tiny = std::numeric_limits<float>::denorm_min();
  // What the FPU sees under DAZ, and what the exact code reads.
  EXPECT_EQ(static_cast<double>(tiny), 0.0);
  EXPECT_EQ(exact::to_double_exact(tiny), 0x1p-149);
  EXPECT_EQ(exact::to_double_exact(-0x1.8p-130f), -0x1.8p-130);
  EXPECT_EQ(exact::to_double_exact(-0.0f), 0.0);
  EXPECT_TRUE(std::signbit(exact::to_double_exact(-0.0f)));
  EXPECT_EQ(exact::to_double_exact(std::numeric_limits<float>::max()), 0x1.fffffep127);
  EXPECT_EQ(exact::to_double_exact(std::numeric_limits<float>::infinity()), std::numeric_limits<double>::infinity());
}

TEST(ExactNumber, QuotientsRoundToNearestEven) {
  EXPECT_TRUE(same_bits(round_quotient_to_float(1, 3), 0x1.555556p-2f));
  EXPECT_TRUE(same_bits(round_quotient_to_float(-1, 3), -0x1.555556p-2f));
  EXPECT_TRUE(same_bits(round_quotient_to_float(2, -3), -0x1.555556p-1f));
  // 1 + 2^-24 lies halfway between 1 and 1 + 2^-23: the even neighbour, 1. 1 + 3 * 2^-24: 1 + 2^-22.
  EXPECT_EQ(round_quotient_to_float(pow2(24) + 1, pow2(24)), 1.0f);
  EXPECT_EQ(round_quotient_to_float(pow2(24) + 3, pow2(24)), 1.0f + 0x1p-22f);
  // Just above the midpoint rounds up.
  EXPECT_EQ(round_quotient_to_float(pow2(60) + pow2(36) + 1, pow2(60)), 1.0f + 0x1p-23f);
  EXPECT_EQ(round_quotient_to_float(0, 7), 0.0f);
}

TEST(ExactNumber, QuotientsRoundOntoTheSubnormalGridAndOverflowToInfinity) {
  const float tiny = std::numeric_limits<float>::denorm_min();  // 2^-149
  EXPECT_EQ(round_quotient_to_float(1, pow2(150)), 0.0f);                   // halfway to 2^-149: even 0
  EXPECT_EQ(round_quotient_to_float(pow2(10) + 1, pow2(160)), tiny);         // just above halfway
  EXPECT_EQ(round_quotient_to_float(3, pow2(150)), 2.0f * tiny);             // 1.5 ulp: even 2 ulp
  EXPECT_EQ(round_quotient_to_float(5, pow2(151)), tiny);                    // 1.25 ulp
  EXPECT_EQ(round_quotient_to_float(1, pow2(200)), 0.0f);
  // (2^23 - 1/2) ulp: halfway between the largest subnormal (odd) and 2^-126 (even): carries into the normals.
  EXPECT_EQ(round_quotient_to_float(pow2(24) - 1, pow2(150)), std::numeric_limits<float>::min());
  EXPECT_EQ(round_quotient_to_float(pow2(24) - 3, pow2(150)), 0x1.fffff8p-127f);  // (2^23 - 1.5) ulp: even 2^23 - 2
  // FLT_MAX + half an ulp is a tie whose even neighbour is 2^128: infinity. Just below it: FLT_MAX.
  const mpz_class max_plus_half = pow2(128) - pow2(103);
  EXPECT_EQ(round_quotient_to_float(max_plus_half, 1), std::numeric_limits<float>::infinity());
  EXPECT_EQ(round_quotient_to_float(2 * max_plus_half - 1, 2), std::numeric_limits<float>::max());
  EXPECT_EQ(round_quotient_to_float(-pow2(200), 3), -std::numeric_limits<float>::infinity());
}

const glm::vec3 kP0{0.0f, 0.0f, 0.0f}, kP1{1.0f, 0.0f, 0.0f}, kP2{0.0f, 1.0f, 0.0f};

TEST(ExactTriangle, AnalyticCrossingFromBothSides) {
  const exact::TriangleCrossing front = exact::intersect_triangle_exact(ray_triangle({0.25f, 0.5f, 2.0f}, {0, 0, -1}, kP0, kP1, kP2));
  ASSERT_TRUE(front.hit);
  EXPECT_EQ(front.t, 2.0f);
  EXPECT_EQ(front.u, 0.25f);
  EXPECT_EQ(front.v, 0.5f);
  EXPECT_EQ(front.t_double, 2.0);
  const exact::TriangleCrossing back = exact::intersect_triangle_exact(ray_triangle({0.25f, 0.5f, -1.0f}, {0, 0, 3}, kP0, kP1, kP2));
  ASSERT_TRUE(back.hit);
  EXPECT_TRUE(same_bits(back.t, 0x1.555556p-2f));  // 1/3, correctly rounded
  // A crossing outside the triangle: no hit, but the plane's t and the (clamped) barycentrics are still defined.
  const exact::TriangleCrossing outside = exact::intersect_triangle_exact(ray_triangle({2.0f, 0.5f, 1.0f}, {0, 0, -1}, kP0, kP1, kP2));
  EXPECT_FALSE(outside.hit);
  EXPECT_FALSE(outside.parallel);
  EXPECT_EQ(outside.t, 1.0f);
  EXPECT_EQ(outside.u, 1.0f);  // 2 clamped
  // Parallel: no crossing.
  EXPECT_TRUE(exact::intersect_triangle_exact(ray_triangle({0.25f, 0.25f, 1.0f}, {1, 0, 0}, kP0, kP1, kP2)).parallel);
  EXPECT_FALSE(exact::intersect_triangle_exact(ray_triangle({-1.0f, 0.25f, 0.0f}, {1, 0, 0}, kP0, kP1, kP2)).hit);
}

TEST(ExactTriangle, SubnormalAndHugeCoordinates) {
  // Vertices 2^-140 apart (subnormal floats): every product underflows float, the exact answer is dyadic.
  const glm::vec3 s0{0.0f, 0.0f, 0.0f}, s1{0x1p-140f, 0.0f, 0.0f}, s2{0.0f, 0x1p-140f, 0.0f};
  const exact::TriangleCrossing small = exact::intersect_triangle_exact(ray_triangle({0x1p-142f, 0x1p-142f, 1.0f}, {0, 0, -1}, s0, s1, s2));
  ASSERT_TRUE(small.hit);
  EXPECT_EQ(small.t, 1.0f);
  EXPECT_EQ(small.u, 0.25f);
  EXPECT_EQ(small.v, 0.25f);
  // Vertices at +-2^127, whose float differences overflow.
  const glm::vec3 h0{-0x1p127f, -0x1p127f, 0.0f}, h1{0x1p127f, -0x1p127f, 0.0f}, h2{0.0f, 0x1p127f, 0.0f};
  const exact::TriangleCrossing huge = exact::intersect_triangle_exact(ray_triangle({0.0f, 0.0f, 0x1p126f}, {0, 0, -1}, h0, h1, h2));
  ASSERT_TRUE(huge.hit);
  EXPECT_EQ(huge.t, 0x1p126f);
  EXPECT_EQ(huge.u, 0.25f);
  EXPECT_EQ(huge.v, 0.5f);
  // A crossing beyond float's range: t rounds to infinity.
  EXPECT_EQ(exact::intersect_triangle_exact(ray_triangle({0.0f, 0.0f, 0x1p127f}, {0, 0, -0x1p-20f}, h0, h1, h2)).t,
            std::numeric_limits<float>::infinity());
}

// The fill rule in the exact sheared frame: a ray exactly through a shared edge or vertex of a consistently
// oriented mesh hits exactly one triangle, also for directions whose float shear is inexact (1/3, 1/7).
TEST(ExactTriangle, RaysThroughSharedEdgesAndVerticesHitExactlyOneTriangle) {
  const SceneGeometry grid = grid_mesh(6, 6);
  const TriangleMesh& mesh = grid.meshes[0];
  const std::vector<glm::vec3> dirs = {{0.0f, 0.0f, -1.0f}, {-0.0f, 0.0f, 1.0f}, {1.0f, 2.0f, -4.0f}, {-3.0f, 1.0f, 2.0f},
                                       {2.0f, -2.0f, -1.0f}, {1.0f, 1.0f, -3.0f}, {0.0f, 5.0f, 7.0f}, {7.0f, -3.0f, -3.0f}};
  int rays = 0;
  for (int j = 1; j < 6; ++j)
    for (int i = 1; i < 6; ++i) {
      const float x = static_cast<float>(i), y = static_cast<float>(j);
      for (const glm::vec3 target : {glm::vec3(x, y, 0), glm::vec3(x + 0.5f, y, 0), glm::vec3(x, y + 0.5f, 0),
                                     glm::vec3(x + 0.5f, y + 0.5f, 0)}) {
        for (const glm::vec3& d : dirs) {
          const glm::vec3 o = target - 0.5f * d;  // exact: dyadic components
          int hits = 0;
          for (const glm::uvec3& tri : mesh.indices)
            hits += exact::intersect_triangle_exact(ray_triangle(o, d, mesh.positions[tri.x], mesh.positions[tri.y],
                                                                 mesh.positions[tri.z]))
                        .hit
                        ? 1
                        : 0;
          EXPECT_EQ(hits, 1) << "target (" << target.x << ", " << target.y << ") dir (" << d.x << ", " << d.y << ", "
                             << d.z << ")";
          ++rays;
        }
      }
    }
  EXPECT_EQ(rays, 25 * 4 * 8);
}

// A crossing exactly halfway between two floats: no double-precision estimate with an error bound can decide
// it, so the refinement must take the exact path, which rounds the tie to even.
TEST(TriangleRefine, FallsBackToExactArithmeticOnARoundingTie) {
  // The plane z = -2^-24 seen from z = 1 straight down: t = 1 + 2^-24, halfway between 1 and 1 + 2^-23.
  const glm::dvec3 o(0.25, 0.25, 1.0), d(0.0, 0.0, -1.0);
  const glm::dvec3 p0(0.0, 0.0, -0x1p-24), p1(1.0, 0.0, -0x1p-24), p2(0.0, 1.0, -0x1p-24);
  const std::uint64_t before = refine_detail::exact_fallbacks.load();
  float t = 0.0f, u = 0.0f, v = 0.0f;
  ASSERT_TRUE(refine_triangle_hit(o, d, p0, p1, p2, 0.0f, 2.0f, t, u, v));
  EXPECT_EQ(t, 1.0f);  // the even neighbour
  EXPECT_EQ(u, 0.25f);
  EXPECT_EQ(v, 0.25f);
  EXPECT_GT(refine_detail::exact_fallbacks.load(), before);
  // Just past the tie the answer is the upper float, still decided exactly.
  ASSERT_TRUE(refine_triangle_hit(o, d, glm::dvec3(0.0, 0.0, -0x1.000002p-24), glm::dvec3(1.0, 0.0, -0x1.000002p-24),
                                  glm::dvec3(0.0, 1.0, -0x1.000002p-24), 0.0f, 2.0f, t, u, v));
  EXPECT_EQ(t, 1.0f + 0x1p-23f);
  // An ordinary crossing is certified in double: no exact work.
  const std::uint64_t certified_before = refine_detail::exact_fallbacks.load();
  // (1 + 0.3f itself would be a tie: 0.3f has 25 significant bits after the leading one.)
  const double z = -0.3f, dz = -0.7f;  // floats, like every input
  const glm::dvec3 q0(0.0, 0.0, z), q1(1.0, 0.0, z), q2(0.0, 1.0, z), slanted(0.125, 0.0625, dz);
  ASSERT_TRUE(refine_triangle_hit(o, slanted, q0, q1, q2, 0.0f, 2.0f, t, u, v));
  EXPECT_EQ(refine_detail::exact_fallbacks.load(), certified_before);
  const exact::TriangleCrossing expected = exact::intersect_triangle_exact({o, slanted, q0, q1, q2});
  EXPECT_TRUE(same_bits(t, expected.t));
  EXPECT_TRUE(same_bits(u, expected.u));
  EXPECT_TRUE(same_bits(v, expected.v));
}

// The interval test uses the correctly rounded t: a crossing just inside tmax by less than half an ulp counts.
TEST(TriangleRefine, IntervalTestUsesTheRoundedT) {
  const glm::dvec3 o(0.25, 0.25, 1.0), d(0.0, 0.0, -1.0);
  const glm::dvec3 p0(0.0, 0.0, -0x1p-25), p1(1.0, 0.0, -0x1p-25), p2(0.0, 1.0, -0x1p-25);  // t = 1 + 2^-25
  float t = 0.0f, u = 0.0f, v = 0.0f;
  EXPECT_TRUE(refine_triangle_hit(o, d, p0, p1, p2, 0.0f, 1.0f, t, u, v));
  EXPECT_EQ(t, 1.0f);
  EXPECT_FALSE(refine_triangle_hit(o, d, p0, p1, p2, std::nextafter(1.0f, 2.0f), 2.0f, t, u, v));
}

TEST(ExactSphere, TangentInsideHugeTinyAndIrrationalRoots) {
  // Tangent at the top: one crossing, t = 5, normal +Y, v = 0 (theta from +Y).
  exact::RaySphere tangent{{0.0, 1.0, -5.0}, {0.0, 0.0, 1.0}, {0.0, 0.0, 0.0}, 1.0};
  const exact::SphereCrossing c = exact::intersect_sphere_exact(tangent);
  ASSERT_TRUE(c.real);
  EXPECT_TRUE(c.tangent);
  EXPECT_EQ(c.t_near, 5.0f);
  EXPECT_EQ(c.t_far, 5.0f);
  glm::vec3 ng;
  float u = 0.0f, v = 0.0f;
  exact::sphere_attributes_exact(tangent, false, ng, u, v);
  EXPECT_EQ(ng, glm::vec3(0.0f, 1.0f, 0.0f));
  EXPECT_EQ(v, 0.0f);
  // Just past tangency: a miss.
  EXPECT_FALSE(exact::intersect_sphere_exact({{0.0, 1.0 + 0x1p-23, -5.0}, {0.0, 0.0, 1.0}, {0.0, 0.0, 0.0}, 1.0}).real);
  // From the center: roots -r/|d| and r/|d|, exit normal along d.
  exact::RaySphere inside{{0.0, 0.0, 0.0}, {0.0, 0.0, 2.0}, {0.0, 0.0, 0.0}, 3.0};
  const exact::SphereCrossing i = exact::intersect_sphere_exact(inside);
  EXPECT_EQ(i.t_near, -1.5f);
  EXPECT_EQ(i.t_far, 1.5f);
  exact::sphere_attributes_exact(inside, true, ng, u, v);
  EXPECT_EQ(ng, glm::vec3(0.0f, 0.0f, 1.0f));
  EXPECT_EQ(v, 0.5f);
  EXPECT_EQ(u, 0.25f);  // phi = atan2(1, 0) = pi/2
  // A huge sphere (r = 1e5) seen from 1e-3 above its top: t is the float 1e-3 itself.
  const float above = 1e-3f;
  const exact::SphereCrossing huge = exact::intersect_sphere_exact(
      {{0.0, exact::to_double_exact(above), 0.0}, {0.0, -1.0, 0.0}, {0.0, -1e5, 0.0}, 1e5});
  EXPECT_EQ(huge.t_near, above);
  // A tiny far sphere (r = 2^-7 at 2^13) head on: t = 2^13 - 2^-7, representable.
  EXPECT_EQ(exact::intersect_sphere_exact({{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0x1p13, 0.0, 0.0}, 0x1p-7}).t_near,
            0x1p13f - 0x1p-7f);
  // Irrational roots 10 -+ sqrt(3)/2: correctly rounded (the double estimate is 1e-16 from them, nowhere near a
  // float midpoint, so rounding it once gives the reference).
  const exact::SphereCrossing irr = exact::intersect_sphere_exact({{0.0, 0.5, -10.0}, {0.0, 0.0, 1.0}, {0.0, 0.0, 0.0}, 1.0});
  EXPECT_EQ(irr.t_near, static_cast<float>(10.0 - std::sqrt(0.75)));
  EXPECT_EQ(irr.t_far, static_cast<float>(10.0 + std::sqrt(0.75)));
  EXPECT_FALSE(irr.tangent);
}

}  // namespace
}  // namespace twinray
