#include "backends/plugin/worker/fp_environment.h"

#if defined(__SSE__) || defined(__x86_64__)
#include <xmmintrin.h>
#define TWINRAY_HAVE_MXCSR 1
#else
#include <cfenv>
#endif

namespace twinray::plugin_worker {

namespace {

#if TWINRAY_HAVE_MXCSR
// MXCSR: bits 0-5 are the sticky exception flags (not compared), 6 DAZ, 7-12 the exception masks, 13-14 the
// rounding mode, 15 FTZ.
constexpr std::uint32_t kControlMask = 0xFFC0u;
constexpr std::uint32_t kDaz = 1u << 6;
constexpr std::uint32_t kExceptionMasks = 0x3Fu << 7;
constexpr std::uint32_t kRounding = 3u << 13;
constexpr std::uint32_t kFtz = 1u << 15;
#endif

void append(std::string& text, const char* what) {
  if (!text.empty()) text += ", ";
  text += what;
}

}  // namespace

std::uint32_t fp_control_bits() {
#if TWINRAY_HAVE_MXCSR
  return _mm_getcsr() & kControlMask;
#else
  return static_cast<std::uint32_t>(fegetround());
#endif
}

void restore_fp_control_bits(std::uint32_t bits) {
#if TWINRAY_HAVE_MXCSR
  _mm_setcsr((_mm_getcsr() & ~kControlMask) | bits);
#else
  fesetround(static_cast<int>(bits));
#endif
}

std::string describe_fp_change(std::uint32_t before, std::uint32_t after) {
  std::string text;
#if TWINRAY_HAVE_MXCSR
  const std::uint32_t changed = before ^ after;
  if ((changed & kFtz) != 0) append(text, (after & kFtz) != 0 ? "flush-to-zero set" : "flush-to-zero cleared");
  if ((changed & kDaz) != 0)
    append(text, (after & kDaz) != 0 ? "denormals-are-zero set" : "denormals-are-zero cleared");
  if ((changed & kRounding) != 0) append(text, "rounding mode changed");
  if ((changed & kExceptionMasks) != 0) append(text, "floating-point exceptions unmasked or masked");
#else
  if (before != after) append(text, "rounding mode changed");
#endif
  return text.empty() ? std::string("floating-point environment changed") : text;
}

}  // namespace twinray::plugin_worker
