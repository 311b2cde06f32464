#pragma once
// Flush-to-zero / denormals-are-zero for the calling thread.
//
// Embree recommends FTZ/DAZ for speed, and a denormal-sensitive comparison between backends only makes
// sense when every backend runs in the same mode. The MXCSR register is per thread, so every thread that
// queries a backend (main thread and TBB workers) enters a ScopedFlushDenormals first.

#include <xmmintrin.h>
#include <pmmintrin.h>

namespace twinray {

class ScopedFlushDenormals {
 public:
  ScopedFlushDenormals() : saved_(_mm_getcsr()) {
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
  }
  ~ScopedFlushDenormals() { _mm_setcsr(saved_); }
  ScopedFlushDenormals(const ScopedFlushDenormals&) = delete;
  ScopedFlushDenormals& operator=(const ScopedFlushDenormals&) = delete;

 private:
  unsigned int saved_;
};

}  // namespace twinray
