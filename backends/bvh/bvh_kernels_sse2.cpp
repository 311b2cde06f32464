// The bvh traversal kernels on sse2: two SSE2 box tests per interior node.
// See backends/simd/isa.h for why the instruction set is chosen by target attributes, not by flags.

#include "backends/bvh/bvh_kernels.h"

#include "backends/bvh/ray_box.h"
#include "backends/bvh/bvh_leaf.h"
#include "core/intersect/sphere_robust.h"
#include "core/intersect/triangle_watertight.h"

#include <algorithm>
#include <cstdint>
#include <type_traits>

namespace twinray::bvh_sse2 {

#define TWINRAY_KERNEL 
#define TWINRAY_BOX_PAIR intersect_box_pair_sse2
#define TWINRAY_BOX_PAIR_RAY BoxPairRaySse2
#include "backends/bvh/bvh_traversal.inl"
#undef TWINRAY_BOX_PAIR
#undef TWINRAY_BOX_PAIR_RAY
#undef TWINRAY_KERNEL

}  // namespace twinray::bvh_sse2
