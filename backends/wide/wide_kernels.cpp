#include "backends/wide/wide_kernels.h"

namespace twinray {

WideKernels wide_kernels(Isa isa, bool triangles, bool spheres, AnyHitOrder order) {
  const bool nearest = order == AnyHitOrder::kNearest;
  WideKernels k;
  switch (isa) {
    case Isa::Avx2:
      k = wide_avx2::kernels(triangles, spheres);
      if (nearest) k.occluded = wide_avx2::nearest_occluded(triangles, spheres);
      return k;
    case Isa::Avx512:
      k = wide_avx512::kernels(triangles, spheres);
      if (nearest) k.occluded = wide_avx512::nearest_occluded(triangles, spheres);
      return k;
    case Isa::Sse2: break;
  }
  k = wide_sse2::kernels(triangles, spheres);
  if (nearest) k.occluded = wide_sse2::nearest_occluded(triangles, spheres);
  return k;
}

}  // namespace twinray
