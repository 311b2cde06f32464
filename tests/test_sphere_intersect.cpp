// Robust ray-sphere test (core/intersect/sphere_robust.h) against a long-double reference, on the cases
// where the textbook formula fails in float: tiny far spheres, huge near spheres, origins inside.

#include "core/intersect/sphere_robust.h"
#include "core/sampling/rng.h"
#include "ray_test_util.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

namespace twinray {
namespace {

using test::kInf;

// Smallest root >= tmin of the same quadratic, textbook formula with the stable q, in long double (64-bit
// mantissa): a reference computed differently from the code under test. NaN when there is none.
long double reference_t(const glm::vec3& org, const glm::vec3& dir, const glm::vec3& center, float radius, float tmin) {
  using LD = long double;
  const LD fx = LD(org.x) - center.x, fy = LD(org.y) - center.y, fz = LD(org.z) - center.z;
  const LD a = LD(dir.x) * dir.x + LD(dir.y) * dir.y + LD(dir.z) * dir.z;
  const LD b = fx * dir.x + fy * dir.y + fz * dir.z;
  const LD c = fx * fx + fy * fy + fz * fz - LD(radius) * radius;
  const LD disc = b * b - a * c;
  if (disc < 0) return std::numeric_limits<long double>::quiet_NaN();
  const LD q = -(b + std::copysign(std::sqrt(disc), b));
  LD t0 = c / q, t1 = q / a;
  if (t0 > t1) std::swap(t0, t1);
  if (t0 >= tmin) return t0;
  if (t1 >= tmin) return t1;
  return std::numeric_limits<long double>::quiet_NaN();
}

glm::vec3 random_unit(Rng& rng) {
  const float z = 1.0f - 2.0f * rng.next_float();
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  const float phi = 2.0f * std::numbers::pi_v<float> * rng.next_float();
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// Distance from the center to the ray's line, in long double: decides whether a ray must hit.
long double closest_approach(const glm::vec3& org, const glm::vec3& dir, const glm::vec3& center) {
  using LD = long double;
  const LD fx = LD(org.x) - center.x, fy = LD(org.y) - center.y, fz = LD(org.z) - center.z;
  const LD a = LD(dir.x) * dir.x + LD(dir.y) * dir.y + LD(dir.z) * dir.z;
  const LD s = (fx * dir.x + fy * dir.y + fz * dir.z) / a;
  const LD lx = fx - s * dir.x, ly = fy - s * dir.y, lz = fz - s * dir.z;
  return std::sqrt(lx * lx + ly * ly + lz * lz);
}

// Fires rays from `org` (outside) at random points within 0.9 radius of the center and compares t and the
// normal with the reference. A float direction aimed at a tiny far sphere is itself off by about a
// radius, so whether a ray must hit is decided by the reference closest approach, with a 0.1% band
// around tangency left out (checked separately in TangentRaysGrazeOnce).
void expect_accurate(const glm::vec3& org, const glm::vec3& center, float radius, std::uint64_t seed) {
  Rng rng(seed, 0);
  int checked_hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const glm::vec3 target = center + 0.9f * radius * rng.next_float() * random_unit(rng);
    const glm::vec3 dir = glm::normalize(target - org);
    const long double approach = closest_approach(org, dir, center) / radius;
    float t = 0.0f;
    const bool hit = intersect_sphere(org, dir, center, radius, 0.0f, kInf, t);
    if (approach > 1.001L) {
      EXPECT_FALSE(hit) << "ray " << i;
      continue;
    }
    if (approach > 0.999L) continue;
    ASSERT_TRUE(hit) << "ray " << i;
    ++checked_hits;
    const long double ref = reference_t(org, dir, center, radius, 0.0f);
    ASSERT_FALSE(std::isnan(ref));
    EXPECT_LT(std::abs((static_cast<long double>(t) - ref) / ref), 1e-6L) << "ray " << i << " t " << t;
    // The normal is unit length and points from the center to the (reference) hit point.
    glm::vec3 n;
    float u, v;
    sphere_hit_attributes(org, dir, t, center, radius, n, u, v);
    EXPECT_NEAR(glm::length(n), 1.0f, 1e-6f);
    const long double px = org.x + ref * dir.x - center.x, py = org.y + ref * dir.y - center.y,
                      pz = org.z + ref * dir.z - center.z;
    const long double len = std::sqrt(px * px + py * py + pz * pz);
    const double cos_angle = static_cast<double>((n.x * px + n.y * py + n.z * pz) / len);
    EXPECT_GT(cos_angle, 1.0 - 1e-6) << "ray " << i;
    EXPECT_TRUE(u >= 0.0f && u < 1.0f && v >= 0.0f && v <= 1.0f);
  }
  EXPECT_GT(checked_hits, 1000);  // the test is about hits: most rays must be checked ones
}

TEST(SphereIntersect, OutsideHitsNearSideWithExactAttributes) {
  float t = 0.0f;
  ASSERT_TRUE(intersect_sphere({0.0f, 0.0f, 5.0f}, {0.0f, 0.0f, -1.0f}, glm::vec3(0.0f), 1.0f, 0.0f, kInf, t));
  EXPECT_EQ(t, 4.0f);
  glm::vec3 n;
  float u, v;
  sphere_hit_attributes({0.0f, 0.0f, 5.0f}, {0.0f, 0.0f, -1.0f}, t, glm::vec3(0.0f), 1.0f, n, u, v);
  EXPECT_EQ(n, glm::vec3(0.0f, 0.0f, 1.0f));
  EXPECT_FLOAT_EQ(u, 0.25f);  // phi = atan2(z, x) = pi/2
  EXPECT_FLOAT_EQ(v, 0.5f);   // theta from +Y = pi/2
  // The poles: theta = 0 at +Y, pi at -Y.
  sphere_hit_attributes({0.0f, 3.0f, 0.0f}, {0.0f, -1.0f, 0.0f}, 2.0f, glm::vec3(0.0f), 1.0f, n, u, v);
  EXPECT_EQ(v, 0.0f);
  sphere_hit_attributes({0.0f, -3.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, 2.0f, glm::vec3(0.0f), 1.0f, n, u, v);
  EXPECT_EQ(v, 1.0f);
  // Unnormalized direction: t in units of |dir|.
  ASSERT_TRUE(intersect_sphere({0.0f, 0.0f, 5.0f}, {0.0f, 0.0f, -4.0f}, glm::vec3(0.0f), 1.0f, 0.0f, kInf, t));
  EXPECT_EQ(t, 1.0f);
}

TEST(SphereIntersect, IntervalSelectsTheQualifyingRoot) {
  const glm::vec3 org{0.0f, 0.0f, 5.0f}, dir{0.0f, 0.0f, -1.0f};
  float t = 0.0f;
  ASSERT_TRUE(intersect_sphere(org, dir, glm::vec3(0.0f), 1.0f, 4.5f, kInf, t));
  EXPECT_EQ(t, 6.0f);  // near root excluded by tmin: the far one
  EXPECT_TRUE(intersect_sphere(org, dir, glm::vec3(0.0f), 1.0f, 0.0f, 4.0f, t));   // closed at tmax
  EXPECT_TRUE(intersect_sphere(org, dir, glm::vec3(0.0f), 1.0f, 6.0f, 6.0f, t));   // closed at tmin
  EXPECT_FALSE(intersect_sphere(org, dir, glm::vec3(0.0f), 1.0f, 0.0f, 3.5f, t));
  EXPECT_FALSE(intersect_sphere(org, dir, glm::vec3(0.0f), 1.0f, 6.5f, kInf, t));
  EXPECT_FALSE(intersect_sphere(org, -dir, glm::vec3(0.0f), 1.0f, 0.0f, kInf, t));  // behind
}

TEST(SphereIntersect, InsideReturnsTheFarRoot) {
  float t = 0.0f;
  ASSERT_TRUE(intersect_sphere(glm::vec3(0.0f), {1.0f, 0.0f, 0.0f}, glm::vec3(0.0f), 2.0f, 0.0f, kInf, t));
  EXPECT_EQ(t, 2.0f);
  ASSERT_TRUE(intersect_sphere({0.5f, 0.0f, 0.0f}, {-1.0f, 0.0f, 0.0f}, glm::vec3(0.0f), 2.0f, 0.0f, kInf, t));
  EXPECT_EQ(t, 2.5f);
  glm::vec3 n;
  float u, v;
  sphere_hit_attributes({0.5f, 0.0f, 0.0f}, {-1.0f, 0.0f, 0.0f}, t, glm::vec3(0.0f), 2.0f, n, u, v);
  EXPECT_EQ(n, glm::vec3(-1.0f, 0.0f, 0.0f));  // outward, not flipped toward the ray
}

TEST(SphereIntersect, TangentRaysGrazeOnce) {
  float t = 0.0f;
  // Exactly tangent: discriminant exactly 0, one (double) root.
  ASSERT_TRUE(intersect_sphere({1.0f, 0.0f, 5.0f}, {0.0f, 0.0f, -1.0f}, glm::vec3(0.0f), 1.0f, 0.0f, kInf, t));
  EXPECT_EQ(t, 5.0f);
  // One ulp outside: miss.
  EXPECT_FALSE(intersect_sphere({std::nextafter(1.0f, 2.0f), 0.0f, 5.0f}, {0.0f, 0.0f, -1.0f}, glm::vec3(0.0f), 1.0f,
                                0.0f, kInf, t));
  // Origin on the sphere, tangent direction: the double root is t = 0.
  ASSERT_TRUE(intersect_sphere({1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, glm::vec3(0.0f), 1.0f, 0.0f, kInf, t));
  EXPECT_EQ(t, 0.0f);
}

TEST(SphereIntersect, TinyFarSphere) {
  expect_accurate(glm::vec3(0.0f), {1e4f, 0.0f, 0.0f}, 1e-3f, 1);
  expect_accurate({3.0f, -2.0f, 1.0f}, {-6000.0f, 7000.0f, 3000.0f}, 1e-3f, 2);
}

TEST(SphereIntersect, HugeSphereOriginOneUnitOutside) {
  const glm::vec3 center{0.0f}, org{0.0f, 0.0f, 100001.0f};
  float t = 0.0f;
  ASSERT_TRUE(intersect_sphere(org, {0.0f, 0.0f, -1.0f}, center, 1e5f, 0.0f, kInf, t));
  EXPECT_EQ(t, 1.0f);
  expect_accurate(org, center, 1e5f, 3);
}

TEST(SphereIntersect, HugeSphereOriginOneUnitInside) {
  const glm::vec3 center{0.0f}, org{0.0f, 99999.0f, 0.0f};
  float t = 0.0f;
  ASSERT_TRUE(intersect_sphere(org, {0.0f, 1.0f, 0.0f}, center, 1e5f, 0.0f, kInf, t));
  EXPECT_EQ(t, 1.0f);
  // Random outward-ish directions: compare with the reference's far root.
  Rng rng(4, 0);
  for (int i = 0; i < 2000; ++i) {
    glm::vec3 dir = random_unit(rng);
    if (dir.y < 0.05f) dir.y = -dir.y + 0.05f;
    dir = glm::normalize(dir);
    ASSERT_TRUE(intersect_sphere(org, dir, center, 1e5f, 0.0f, kInf, t));
    const long double ref = reference_t(org, dir, center, 1e5f, 0.0f);
    EXPECT_LT(std::abs((static_cast<long double>(t) - ref) / ref), 1e-6L) << "ray " << i;
  }
}

TEST(SphereIntersect, NaNRadiusMisses) {
  float t = 0.0f;
  EXPECT_FALSE(intersect_sphere({0.0f, 0.0f, 5.0f}, {0.0f, 0.0f, -1.0f}, glm::vec3(0.0f),
                                std::numeric_limits<float>::quiet_NaN(), 0.0f, kInf, t));
}

}  // namespace
}  // namespace twinray
