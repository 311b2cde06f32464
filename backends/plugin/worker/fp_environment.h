#pragma once
// The floating-point environment a plugin must leave as it found it (docs/plugin-abi.md, "Lifecycle and
// threading", item 5):
// on x86 the control bits of MXCSR (flush-to-zero, denormals-are-zero, rounding mode, exception masks), per
// thread. A plugin that sets flush-to-zero "for speed" in build and leaves it set changes every later float
// operation of that thread (in process: the host's), so the worker compares the control bits after each call
// with those before it and reports a change as a contract violation. The sticky exception flags are not
// compared: raising them (an inexact result, a division by zero in a slab test) is ordinary arithmetic.

#include <cstdint>
#include <string>

namespace twinray::plugin_worker {

// The control bits of this thread's floating-point environment (MXCSR's; elsewhere the rounding mode).
std::uint32_t fp_control_bits();
// Sets them back (after a violation, so the worker's own arithmetic and the next call start from the default).
void restore_fp_control_bits(std::uint32_t bits);
// "flush-to-zero set, denormals-are-zero set" etc.: what differs between `before` and `after`.
std::string describe_fp_change(std::uint32_t before, std::uint32_t after);

}  // namespace twinray::plugin_worker
