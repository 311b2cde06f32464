// Rays as command-line text (core/geometry/ray_text.h): a reproduce line must replay its ray bit for bit.

#include "core/geometry/ray_text.h"
#include "ray_test_util.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace twinray {
namespace {

using test::kInf;
using test::same_bits;

void expect_same_ray(const Ray& a, const Ray& b) {
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(same_bits(a.org[k], b.org[k])) << "org " << k;
    EXPECT_TRUE(same_bits(a.dir[k], b.dir[k])) << "dir " << k;
  }
  EXPECT_TRUE(same_bits(a.tmin, b.tmin));
  EXPECT_TRUE(same_bits(a.tmax, b.tmax));
}

TEST(RayText, HexRoundTripKeepsEveryBit) {
  const Ray rays[] = {
      test::make_ray({0.1f, -0.0f, 3.9f}, {0.0f, -0.0f, -1.0f}, 0.0f, kInf),
      test::make_ray({1e-40f, 1e30f, -7.5f}, {1e-20f, 0x1.fffffep+127f, -0x1p-149f}, 0x1p-126f, 1.0f),
      test::make_ray({-3.0f, 2.0f, 0.333333343f}, {0.5f, 0.25f, 0.125f}, 0.5f, 0.50000006f),
  };
  for (const Ray& r : rays) expect_same_ray(parse_ray(format_ray_hex(r)), r);
}

TEST(RayText, ParsesDecimalsHexAndInfinity) {
  const Ray r = parse_ray("0.5 0.25 3   0x0p+0,-0x0p+0 -1 0 inf");
  EXPECT_EQ(r.org.x, 0.5f);
  EXPECT_EQ(r.org.z, 3.0f);
  EXPECT_FALSE(std::signbit(r.dir.x));
  EXPECT_TRUE(std::signbit(r.dir.y));  // -0 survives
  EXPECT_EQ(r.dir.z, -1.0f);
  EXPECT_EQ(r.tmax, kInf);
  EXPECT_EQ(parse_ray("0.1 0 0 1 0 0 0 1").org.x, 0.1f);  // decimals round to the nearest float
}

TEST(RayText, FormatsSignedZeroAndInfinity) {
  EXPECT_EQ(hex_float(-0.0f), "-0x0p+0");
  EXPECT_EQ(hex_float(1.5f), "0x1.8p+0");
  EXPECT_EQ(hex_float(kInf), "inf");
}

TEST(RayText, RejectsMalformedRays) {
  EXPECT_THROW(parse_ray("1 2 3 4 5 6 7"), std::invalid_argument);
  EXPECT_THROW(parse_ray("1 2 3 4 5 6 7 8 9"), std::invalid_argument);
  EXPECT_THROW(parse_ray("1 2 3 4 5 6 7 x"), std::invalid_argument);
  EXPECT_THROW(parse_ray("1 2 3 4 5 6 7 nan"), std::invalid_argument);
  EXPECT_THROW(parse_ray("1 2 3 4 5 6 7 1e50"), std::invalid_argument);  // overflows a float
  try {
    parse_ray("1 2 3 4 oops 6 7 8");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("dy"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace twinray
