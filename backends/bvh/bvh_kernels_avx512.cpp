// The bvh traversal kernels on avx512: the AVX2 kernels (the same AVX test of both child boxes, ray_box.h) compiled
// for AVX-512 VL, whose 32 vector registers hold the query's constants that the AVX2 build keeps on the stack.
// See backends/simd/isa.h for why the instruction set is chosen by target attributes, not by flags.

#include "backends/bvh/bvh_kernels.h"

#include "backends/bvh/ray_box.h"
#include "backends/bvh/bvh_leaf.h"
#include "core/intersect/sphere_robust.h"
#include "core/intersect/triangle_watertight.h"

#include <algorithm>
#include <cstdint>
#include <type_traits>

namespace twinray::bvh_avx512 {

#define TWINRAY_KERNEL TWINRAY_TARGET_AVX512
#define TWINRAY_BOX_PAIR intersect_box_pair_avx2
#define TWINRAY_BOX_PAIR_RAY BoxPairRayAvx2
#include "backends/bvh/bvh_traversal.inl"
#undef TWINRAY_BOX_PAIR
#undef TWINRAY_BOX_PAIR_RAY
#undef TWINRAY_KERNEL

}  // namespace twinray::bvh_avx512
