#include "backends/bvh/bvh_kernels.h"

namespace twinray {

BvhKernels bvh_kernels(Isa isa, bool triangles, bool spheres) {
  return isa == Isa::Sse2 ? bvh_sse2::kernels(triangles, spheres) : bvh_avx2::kernels(triangles, spheres);
}

}  // namespace twinray
