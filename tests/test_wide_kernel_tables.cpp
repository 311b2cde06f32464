// The bvh8 kernels' small parts that are not traversal: the SSE2 ray check, the push order, the octant
// rows and the leaf references' decoding. Traversal itself is checked against brute force (BvhVsBrute, BackendsAgree).

#include "backends/wide/wide_leaf_ref.h"
#include "backends/wide/wide_node.h"
#include "backends/wide/wide_octant_rows.h"
#include "backends/wide/wide_push_order.h"
#include "backends/wide/wide_ray_check.h"
#include "core/geometry/ray.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace twinray {
namespace {

std::vector<float> special_values() {
  const float inf = std::numeric_limits<float>::infinity();
  return {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, 1e-40f, -1e-40f, std::numeric_limits<float>::max(), inf, -inf,
          std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::quiet_NaN()};
}

float& field(Ray& r, int i) {
  switch (i) {
    case 0: return r.org.x;
    case 1: return r.org.y;
    case 2: return r.org.z;
    case 3: return r.tmin;
    case 4: return r.dir.x;
    case 5: return r.dir.y;
    case 6: return r.dir.z;
    default: return r.tmax;
  }
}

TEST(WideRayCheck, AgreesWithIsValidRayOnEverySpecialValueOfEachField) {
  const Ray base{glm::vec3(0.25f, -2.0f, 3.0f), 0.0f, glm::vec3(0.0f, 0.5f, -1.0f), 10.0f};
  ASSERT_TRUE(wide_ray_is_valid(base));
  int invalid = 0;
  for (int i = 0; i < 8; ++i)
    for (const float x : special_values()) {
      Ray r = base;
      field(r, i) = x;
      EXPECT_EQ(wide_ray_is_valid(r), is_valid_ray(r)) << "field " << i << " = " << x;
      invalid += is_valid_ray(r) ? 0 : 1;
    }
  EXPECT_GT(invalid, 30);  // the cases exercise both answers
}

TEST(WideRayCheck, AgreesWithIsValidRayOnEveryDirectionAndInterval) {
  const std::vector<float> values = special_values();
  for (const float x : values)
    for (const float y : values)
      for (const float z : values) {
        const Ray r{glm::vec3(1.0f), 0.0f, glm::vec3(x, y, z), 1.0f};
        EXPECT_EQ(wide_ray_is_valid(r), is_valid_ray(r)) << "dir " << x << " " << y << " " << z;
      }
  for (const float tmin : values)
    for (const float tmax : values) {
      const Ray r{glm::vec3(1.0f), tmin, glm::vec3(0.0f, 0.0f, 1.0f), tmax};
      EXPECT_EQ(wide_ray_is_valid(r), is_valid_ray(r)) << "tmin " << tmin << " tmax " << tmax;
    }
}

TEST(WidePushOrder, ListsEachMasksSlotsHighestFirst) {
  for (unsigned mask = 0; mask < 256; ++mask) {
    const std::uint64_t bytes = kWideDescendingSlots[mask];
    const int n = std::popcount(mask);
    int previous = 8;
    for (int k = 0; k < n; ++k) {
      const int slot = static_cast<int>((bytes >> (8 * k)) & 0xFFu);
      EXPECT_LT(slot, previous) << "mask " << mask;
      EXPECT_TRUE((mask >> slot) & 1u) << "mask " << mask;
      previous = slot;
    }
    EXPECT_EQ(n == 8 ? 0 : bytes >> (8 * n), 0u) << "mask " << mask;
  }
}

TEST(WideOctantRows, NearPlaneIsTheLowOneExactlyWhenTheDirectionIsPositive) {
  for (unsigned octant = 0; octant < 8; ++octant)
    for (int a = 0; a < 3; ++a) {
      const bool negative = (octant >> a) & 1u;
      EXPECT_EQ(kWideOctantRows[octant].near_row[a], negative ? WideNode::hi_row(a) : WideNode::lo_row(a));
      EXPECT_EQ(kWideOctantRows[octant].far_row[a], negative ? WideNode::lo_row(a) : WideNode::hi_row(a));
    }
}

// Every triangle leaf a reference can name (each count, each starting lane, blocks at both ends of the 24-bit
// range): the decode gives the first block, the run of `count` lanes from the first lane, and back the slot and
// the count; a sphere leaf keeps its 26-bit first sphere; inner references are not leaves.
TEST(WideLeafRef, TriangleLeafDecodesToItsBlockAndLanes) {
  const std::uint32_t blocks[] = {0u, 1u, 12345u, WideRef::kBlockMask - 1, WideRef::kBlockMask};
  for (const std::uint32_t block : blocks)
    for (std::uint32_t lane = 0; lane < kTriangleBlockLanes; ++lane)
      for (std::uint32_t count = 1; count <= WideRef::kMaxLeafCount; ++count) {
        const std::uint32_t slot = block * kTriangleBlockLanes + lane;
        const std::uint32_t ref = WideRef::leaf(slot, count, false);
        ASSERT_TRUE(WideRef::is_leaf(ref));
        ASSERT_FALSE(WideRef::is_sphere_leaf(ref));
        EXPECT_EQ(WideRef::count(ref), count);
        EXPECT_EQ(WideRef::first(ref), slot);
        EXPECT_EQ(WideRef::first_slot(ref), slot);
        const WideTriangleLeaf leaf = wide_triangle_leaf(ref);
        EXPECT_EQ(leaf.block, block) << slot << " " << count;
        std::uint32_t expected = 0;
        for (std::uint32_t i = 0; i < count; ++i) expected |= 1u << (lane + i);
        EXPECT_EQ(leaf.lanes, expected) << slot << " " << count;
      }
  for (const std::uint32_t first : {0u, 1u, 7u, WideRef::kFirstMask})
    for (std::uint32_t count = 1; count <= WideRef::kMaxLeafCount; ++count) {
      const std::uint32_t ref = WideRef::leaf(first, count, true);
      EXPECT_TRUE(WideRef::is_leaf(ref) && WideRef::is_sphere_leaf(ref));
      EXPECT_EQ(WideRef::first(ref), first);
      EXPECT_EQ(WideRef::first_sphere(ref), first);
      EXPECT_EQ(WideRef::count(ref), count);
    }
  // The table is zero where no triangle leaf's top byte lands (inner and sphere references).
  for (std::uint32_t top = 0; top < 256; ++top) {
    const bool triangle_leaf = WideRef::is_leaf(top << 24) && !WideRef::is_sphere_leaf(top << 24);
    if (!triangle_leaf) {
      EXPECT_EQ(kWideLeafLanes[top], 0u) << top;
    }
  }
}

}  // namespace
}  // namespace twinray
