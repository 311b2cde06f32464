#pragma once
// Whether this program was built with AddressSanitizer (scripts/sanitize.sh). The plugin worker adapts to it:
// ASan's shadow memory reserves terabytes of address space at start, so RLIMIT_AS must be counted from there,
// and ASan's own SEGV/abort handlers must stay out of the way of the worker's crash reporting
// (docs/plugin-abi.md, "Isolation and sandbox").

namespace twinray {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
#else
inline constexpr bool kAddressSanitizer = false;
#endif

}  // namespace twinray
