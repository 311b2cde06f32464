#pragma once
// The wide backend's traversal kernels (wide_traversal.inl), compiled once per instruction set.
//
// What differs between the sets is only the eight-box slab test and reading the children's leaf bits
// (wide_kernels_<isa>.cpp); traversal, ordering and the leaf tests are the same code. All sets give
// bit-identical answers (tests/test_wide_bvh.cpp runs every set this CPU has).

#include "backends/bvh/primitive_store.h"
#include "backends/simd/isa.h"
#include "backends/wide/wide_node.h"
#include "core/backend/backend.h"
#include "core/geometry/hit.h"
#include "core/geometry/ray.h"


namespace twinray {

struct WideView {
  const WideNode* nodes;  // nodes[0] is the root; never empty when a kernel runs
  const PrimitiveStore* prims;
};

// Closest hit (fills `hit` completely or leaves it a miss), closest hit with t and ids only (u, v and ng
// left as a miss has them: Backend::intersect_ids) and any hit. Each checks its ray first (an invalid ray
// misses: it must not sweep the tree), in the kernel's own instruction set, and takes the view by value (two
// pointers in two registers): the backend's wrapper then only forwards its arguments.
using WideOccludedKernel = bool (*)(WideView bvh, const Ray& ray, QueryStats* stats);
struct WideKernels {
  bool (*intersect)(WideView bvh, const Ray& ray, Hit& hit, QueryStats* stats) = nullptr;
  bool (*intersect_ids)(WideView bvh, const Ray& ray, Hit& hit, QueryStats* stats) = nullptr;
  WideOccludedKernel occluded = nullptr;
};

// Which hit inner child the any-hit traversal visits first at a node (the others are pushed in stored order):
// the one stored first (larger weight, SATO: wide_collapse.h), or the one the ray enters first. Chosen per tree
// at build time (WideBuildOptions::any_hit_order, wide_any_order.h); answers are the same.
enum class AnyHitOrder { kStored, kNearest };

// The kernels for scenes with the given primitive kinds (at least one) on `isa`.
WideKernels wide_kernels(Isa isa, bool triangles, bool spheres, AnyHitOrder order = AnyHitOrder::kStored);

namespace wide_sse2 {
WideKernels kernels(bool triangles, bool spheres);  // any hit in stored order
WideOccludedKernel nearest_occluded(bool triangles, bool spheres);  // wide_kernels_sse2_nearest.cpp
}
namespace wide_avx2 {
WideKernels kernels(bool triangles, bool spheres);  // any hit in stored order
WideOccludedKernel nearest_occluded(bool triangles, bool spheres);  // wide_kernels_avx2_nearest.cpp
}
namespace wide_avx512 {
WideKernels kernels(bool triangles, bool spheres);  // any hit in stored order
WideOccludedKernel nearest_occluded(bool triangles, bool spheres);  // wide_kernels_avx512_nearest.cpp
}

}  // namespace twinray
