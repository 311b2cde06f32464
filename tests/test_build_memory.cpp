// The build's large arrays (bvh_builder_memory.h): aligned, writable, movable, on either path.

#include "backends/bvh/bvh_builder_memory.h"

#include <gtest/gtest.h>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include <cstdint>
#include <utility>
#include <vector>

namespace twinray {
namespace {

struct alignas(32) Element32 {
  std::uint32_t v[8];
};

// Writes every element, then reads them back: the whole array is mapped and private.
void expect_writable(BuildArray<Element32>& a) {
  for (std::size_t i = 0; i < a.size(); ++i) a[i].v[i % 8] = static_cast<std::uint32_t>(i);
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < a.size(); ++i) wrong += a[i].v[i % 8] != static_cast<std::uint32_t>(i);
  EXPECT_EQ(wrong, 0u);
}

TEST(BuildMemory, SmallArraysAreHeapMemoryAlignedForTheirElements) {
  BuildArray<Element32> a(1000);  // 32 KB: the heap
  ASSERT_NE(a.get(), nullptr);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(a.get()) % 64, 0u);
  expect_writable(a);
}

TEST(BuildMemory, LargeArraysStartOnAHugePageBoundary) {
#if !(defined(__linux__) && defined(MADV_HUGEPAGE))
  GTEST_SKIP() << "no MADV_HUGEPAGE here: large arrays take the heap path, aligned only for their elements";
#endif
  const std::size_t n = (std::size_t{5} << 20) / sizeof(Element32) + 3;  // 5 MB and a bit: its own mapping
  BuildArray<Element32> a(n);
  ASSERT_NE(a.get(), nullptr);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(a.get()) % (std::uintptr_t{1} << 21), 0u);
  expect_writable(a);
  // Moving hands the mapping over; the moved-from array owns nothing (its destructor frees nothing).
  Element32* const data = a.get();
  BuildArray<Element32> b(std::move(a));
  EXPECT_EQ(b.get(), data);
  EXPECT_EQ(b.size(), n);
  EXPECT_EQ(a.get(), nullptr);  // NOLINT(bugprone-use-after-move): the state after a move is the contract
  b = BuildArray<Element32>(10);
  EXPECT_EQ(b.size(), 10u);
}

TEST(BuildMemory, AdvisingForeignMemoryChangesNothing) {
  std::vector<std::uint32_t> v(std::size_t{3} << 20, 7u);  // 12 MB, not aligned to 2 MB
  advise_huge_pages(v.data(), v.size() * sizeof(std::uint32_t));
  advise_huge_pages(nullptr, 0);
  std::size_t wrong = 0;
  for (const std::uint32_t x : v) wrong += x != 7u;
  EXPECT_EQ(wrong, 0u);
}

}  // namespace
}  // namespace twinray
