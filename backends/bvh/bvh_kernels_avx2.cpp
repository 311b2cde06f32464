// The bvh traversal kernels on avx2: one AVX test of both child boxes per interior node, the kernels compiled for AVX2.
// See backends/simd/isa.h for why the instruction set is chosen by target attributes, not by flags.

#include "backends/bvh/bvh_kernels.h"

#include "backends/bvh/ray_box.h"
#include "backends/bvh/bvh_leaf.h"
#include "core/intersect/sphere_robust.h"
#include "core/intersect/triangle_watertight.h"

#include <algorithm>
#include <cstdint>
#include <type_traits>

namespace twinray::bvh_avx2 {

#define TWINRAY_KERNEL TWINRAY_TARGET_AVX2
#define TWINRAY_BOX_PAIR intersect_box_pair_avx2
#define TWINRAY_BOX_PAIR_RAY BoxPairRayAvx2
#include "backends/bvh/bvh_traversal.inl"
#undef TWINRAY_BOX_PAIR
#undef TWINRAY_BOX_PAIR_RAY
#undef TWINRAY_KERNEL

}  // namespace twinray::bvh_avx2
