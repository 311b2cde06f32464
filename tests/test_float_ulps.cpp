// float_ulp_distance: the count of floats between two floats, across zero and the subnormals.

#include "core/util/float_ulps.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace twinray {
namespace {

TEST(FloatUlps, CountsTheFloatsBetweenTwoFloats) {
  EXPECT_EQ(float_ulp_distance(1.0f, 1.0f), 0);
  EXPECT_EQ(float_ulp_distance(1.0f, std::nextafter(1.0f, 2.0f)), 1);
  EXPECT_EQ(float_ulp_distance(std::nextafter(1.0f, 0.0f), 1.0f), 1);  // symmetric, and the spacing halves below 1
  EXPECT_EQ(float_ulp_distance(1.0f, 2.0f), 1 << 23);                   // one binade
  EXPECT_EQ(float_ulp_distance(0.0f, -0.0f), 0);
  const float tiny = std::numeric_limits<float>::denorm_min();
  EXPECT_EQ(float_ulp_distance(-tiny, tiny), 2);                        // -tiny, +-0, +tiny
  EXPECT_EQ(float_ulp_distance(-1.0f, 1.0f), 2 * float_ulp_distance(0.0f, 1.0f));
  EXPECT_EQ(float_ulp_distance(0.0f, std::numeric_limits<float>::max()), 0x7f7fffff);
}

}  // namespace
}  // namespace twinray
