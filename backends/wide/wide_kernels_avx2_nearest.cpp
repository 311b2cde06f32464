// The nearest-first any-hit kernels (AnyHitOrder::kNearest, wide_any_order.h) on AVX2: wide_kernels_avx2.cpp
// compiled again with only them as entry points. In their own unit, because GCC's inlining budget is per unit:
// with them beside the other kernels it inlined differently there (order_children out of line: dragon
// closest-hit primary rays +29 instructions; forced inline, still +1%: docs/bvh-backend.md, eleventh round),
// and here the closest-hit and stored-order any-hit kernels stay exactly as without them.
#define TWINRAY_WIDE_NEAREST_UNIT
#include "backends/wide/wide_kernels_avx2.cpp"
