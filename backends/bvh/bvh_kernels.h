#pragma once
// The bvh backend's traversal kernels (bvh_traversal.inl), one set per instruction set.
//
// The kernels differ only in the child-pair box test: two SSE2 tests, or one AVX test of both boxes
// (ray_box.h). The answers are bit-identical either way (tested). The AVX-512 set is the AVX2 source (a pair of
// boxes fills only 256 bits) compiled for AVX-512 VL: its 32 vector registers keep the query's broadcast
// constants and the stack's size in registers, which the AVX2 build spills (eleventh round,
// docs/bvh-backend.md: 1 to 5% less time on primary rays).

#include "backends/bvh/bvh_node.h"
#include "backends/bvh/primitive_store.h"
#include "backends/simd/isa.h"
#include "core/backend/backend.h"
#include "core/geometry/hit.h"
#include "core/geometry/ray.h"

#include <span>

namespace twinray {

struct BvhView {
  std::span<const BvhNode> nodes;
  const PrimitiveStore* prims;
};

// Closest hit (fills `hit` completely or leaves it a miss) and any hit, for a valid ray.
struct BvhKernels {
  bool (*intersect)(const BvhView& bvh, const Ray& ray, Hit& hit, QueryStats* stats) = nullptr;
  bool (*occluded)(const BvhView& bvh, const Ray& ray, QueryStats* stats) = nullptr;
};

// The kernels for scenes with the given primitive kinds (at least one), on `isa` (Avx512 gives Avx2's).
BvhKernels bvh_kernels(Isa isa, bool triangles, bool spheres);

namespace bvh_sse2 {
BvhKernels kernels(bool triangles, bool spheres);
}
namespace bvh_avx2 {
BvhKernels kernels(bool triangles, bool spheres);
}
namespace bvh_avx512 {
BvhKernels kernels(bool triangles, bool spheres);
}

}  // namespace twinray
