#include "backends/wide/wide_kernels.h"

namespace twinray {

WideKernels wide_kernels(Isa isa, bool triangles, bool spheres, AnyHitOrder order) {
  switch (isa) {
    case Isa::Sse2: return wide_sse2::kernels(triangles, spheres, order);
    case Isa::Avx2: return wide_avx2::kernels(triangles, spheres, order);
    case Isa::Avx512: return wide_avx512::kernels(triangles, spheres, order);
  }
  return wide_sse2::kernels(triangles, spheres, order);
}

}  // namespace twinray
