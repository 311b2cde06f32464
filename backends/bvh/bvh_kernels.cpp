#include "backends/bvh/bvh_kernels.h"

namespace twinray {

BvhKernels bvh_kernels(Isa isa, bool triangles, bool spheres) {
  if (isa == Isa::Sse2) return bvh_sse2::kernels(triangles, spheres);
  return isa == Isa::Avx512 ? bvh_avx512::kernels(triangles, spheres) : bvh_avx2::kernels(triangles, spheres);
}

}  // namespace twinray
