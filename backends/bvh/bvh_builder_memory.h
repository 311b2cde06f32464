#pragma once
// Large arrays of a build on transparent huge pages.
//
// A build's large arrays are fresh memory: every 4 KiB page of them is a page fault whose kernel work
// (the fault itself, zeroing the page, mapping it) runs on the thread that first touches it. A
// one-million-triangle bvh8 build took about 50 000 of them, a quarter of the build's profile samples
// (docs/bvh-backend.md, "Build", ninth round); Embree's builder asks for 2 MiB pages and takes a few
// hundred. Memory advised as huge pages (madvise MADV_HUGEPAGE; Linux's transparent huge pages in their
// usual "madvise" mode) maps 2 MiB per fault: the zeroing stays, the per-page overhead and the TLB misses
// of the passes over the arrays go. Only where the memory lies changes, never its contents, so the trees
// are the same bytes.

#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>

namespace twinray {

// Advises the 2 MiB-aligned part of [data, data + bytes) as huge-page memory, before it is first touched
// (for buffers the build does not allocate itself, such as a std::vector's). Only advice: arrays of less
// than two huge pages, systems without transparent huge pages and memory the kernel refuses are left on
// small pages.
void advise_huge_pages(const void* data, std::size_t bytes);

// Resizes an empty std::vector (any allocator) to n elements with its memory advised as huge pages before
// resize() first touches it: reserve, advise, resize.
template <class Vector>
void resize_on_huge_pages(Vector& v, std::size_t n) {
  v.reserve(n);
  advise_huge_pages(v.data(), n * sizeof(typename Vector::value_type));
  v.resize(n);
}

// Raw memory for a build array: from 4 MiB on, its own 2 MiB-aligned mapping advised as huge pages (so no
// unaligned edge stays on small pages), else the ordinary heap. Uninitialised, 64-byte aligned at least.
void* allocate_build_memory(std::size_t bytes);
void free_build_memory(void* data, std::size_t bytes) noexcept;
// Gives the pages of build memory `data` (allocated for `bytes`) after its first `used` bytes back to the
// system, keeping the allocation: for an array that turned out smaller than its worst case. Those bytes
// must not be read again (they would read as zeros). Heap memory is left alone.
void release_build_memory_tail(void* data, std::size_t used, std::size_t bytes) noexcept;

// An uninitialised array of n trivially constructible T on build memory (like new T[n], which leaves
// such T uninitialised too): every element must be written before it is read.
template <class T>
class BuildArray {
  static_assert(std::is_trivially_default_constructible_v<T> && std::is_trivially_destructible_v<T>,
                "a build array neither constructs nor destroys its elements");
  static_assert(alignof(T) <= 64, "build memory is 64-byte aligned");

 public:
  BuildArray() = default;
  explicit BuildArray(std::size_t n) : data_(static_cast<T*>(allocate_build_memory(n * sizeof(T)))), n_(n) {}
  BuildArray(BuildArray&& other) noexcept : data_(std::exchange(other.data_, nullptr)), n_(std::exchange(other.n_, 0)) {}
  BuildArray& operator=(BuildArray&& other) noexcept {
    if (this != &other) {
      reset();
      data_ = std::exchange(other.data_, nullptr);
      n_ = std::exchange(other.n_, 0);
    }
    return *this;
  }
  BuildArray(const BuildArray&) = delete;
  BuildArray& operator=(const BuildArray&) = delete;
  ~BuildArray() { reset(); }

  void reset() noexcept {
    if (data_ != nullptr) free_build_memory(data_, n_ * sizeof(T));
    data_ = nullptr;
    n_ = 0;
  }
  T* get() const { return data_; }
  std::size_t size() const { return n_; }
  T& operator[](std::size_t i) const { return data_[i]; }

 private:
  T* data_ = nullptr;
  std::size_t n_ = 0;
};

// A std::vector allocator on build memory whose resize() leaves trivially constructible elements
// uninitialised (default-initialised, where std::allocator value-initialises, i.e. zero-fills: a pass
// that first-touches every page on one thread). For arrays whose every element is written before it is
// read.
template <class T>
struct BuildAllocator {
  using value_type = T;
  BuildAllocator() = default;
  template <class U>
  BuildAllocator(const BuildAllocator<U>&) noexcept {}  // NOLINT(google-explicit-constructor): rebinding
  T* allocate(std::size_t n) { return static_cast<T*>(allocate_build_memory(n * sizeof(T))); }
  void deallocate(T* p, std::size_t n) noexcept { free_build_memory(p, n * sizeof(T)); }
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  friend bool operator==(const BuildAllocator&, const BuildAllocator&) { return true; }
};

}  // namespace twinray
