#include "backends/bvh/bvh_builder_memory.h"

#include <cstdint>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace twinray {

namespace {

constexpr std::size_t kHugePage = std::size_t{1} << 21;
// From this size an array gets its own mapping: at least two huge pages, so that the mapping's rounding
// (at most one huge page) wastes at most a third of it, and never a byte of touched memory.
constexpr std::size_t kOwnMappingFrom = 2 * kHugePage;
constexpr std::align_val_t kHeapAlignment{64};

std::size_t round_up(std::size_t bytes, std::size_t to) { return (bytes + to - 1) / to * to; }

}  // namespace

void advise_huge_pages(const void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (data == nullptr || bytes < 2 * kHugePage) return;
  const auto begin = reinterpret_cast<std::uintptr_t>(data);
  const std::uintptr_t first = (begin + kHugePage - 1) & ~std::uintptr_t{kHugePage - 1};
  const std::uintptr_t last = (begin + bytes) & ~std::uintptr_t{kHugePage - 1};
  if (last <= first) return;
  (void)madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);  // only advice
#else
  (void)data;
  (void)bytes;
#endif
}

void* allocate_build_memory(std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (bytes >= kOwnMappingFrom) {
    // Map one huge page more than needed, then unmap the head before the first 2 MiB boundary and the
    // tail after the rounded size: what is left is aligned and a whole number of huge pages.
    const std::size_t size = round_up(bytes, kHugePage);
    void* const raw = mmap(nullptr, size + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (raw == MAP_FAILED) throw std::bad_alloc();
    const auto begin = reinterpret_cast<std::uintptr_t>(raw);
    const std::uintptr_t aligned = (begin + kHugePage - 1) & ~std::uintptr_t{kHugePage - 1};
    if (aligned > begin) munmap(raw, aligned - begin);
    const std::uintptr_t end = begin + size + kHugePage;
    if (end > aligned + size) munmap(reinterpret_cast<void*>(aligned + size), end - (aligned + size));
    (void)madvise(reinterpret_cast<void*>(aligned), size, MADV_HUGEPAGE);  // only advice
    return reinterpret_cast<void*>(aligned);
  }
#endif
  return ::operator new(bytes == 0 ? 1 : bytes, kHeapAlignment);
}

void release_build_memory_tail(void* data, std::size_t used, std::size_t bytes) noexcept {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (data == nullptr || bytes < kOwnMappingFrom) return;
  const std::size_t first = round_up(used, kHugePage), size = round_up(bytes, kHugePage);
  if (first < size) (void)madvise(static_cast<char*>(data) + first, size - first, MADV_DONTNEED);
#else
  (void)data;
  (void)used;
  (void)bytes;
#endif
}

void free_build_memory(void* data, std::size_t bytes) noexcept {
  if (data == nullptr) return;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (bytes >= kOwnMappingFrom) {
    munmap(data, round_up(bytes, kHugePage));
    return;
  }
#endif
  ::operator delete(data, kHeapAlignment);
}

}  // namespace twinray
