#pragma once
// Which x86 instruction set the BVH kernels run on, chosen once at run time.
//
// The build is portable x86-64 (SSE2 baseline): no -march flag, so one binary runs on any x86-64 CPU.
// The traversal kernels that profit from wider vectors are compiled a second and third time inside one
// translation unit per instruction set, each function marked with a target attribute (TWINRAY_TARGET_*
// below), and the backend picks the widest set this CPU and its operating system support.
//
// Why target attributes inside ordinary translation units, not separate files built with -mavx2: inline
// functions from shared headers (std::, glm::, the triangle test) are emitted once per translation unit and
// the linker keeps one copy; a copy compiled with -mavx2 could then be the one an SSE2 caller runs, which
// faults on a CPU without AVX2. Functions outside a target attribute stay SSE2 wherever they are
// compiled, and GCC and clang inline them into AVX2 / AVX-512 callers (a callee whose target is a subset
// of its caller's may be inlined).
//
// FMA is deliberately left out of the target lists: the project rounds every product in intersection
// code (-ffp-contract=off) so that all backends and all instruction sets give bit-identical answers.
//
// TWINRAY_ISA=sse2|avx2|avx512 lowers the choice (to test a narrower path on a wider CPU); asking for more
// than the CPU has is an error.

#include <optional>
#include <string_view>
#include <vector>

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
// x86-64-v3 without FMA (Haswell / Zen 1 and later).
#define TWINRAY_TARGET_AVX2 __attribute__((target("avx2,bmi,bmi2,lzcnt,popcnt")))
// x86-64-v4: AVX-512 F, VL, DQ, BW (Skylake-SP / Zen 4 and later).
#define TWINRAY_TARGET_AVX512 \
  __attribute__((target("avx512f,avx512vl,avx512dq,avx512bw,avx2,bmi,bmi2,lzcnt,popcnt")))
#else
#error "twinray's BVH kernels need GCC or clang on x86-64"
#endif

namespace twinray {

enum class Isa { Sse2 = 0, Avx2 = 1, Avx512 = 2 };

std::string_view to_string(Isa isa);
// "sse2", "avx2", "avx512"; nullopt for anything else.
std::optional<Isa> parse_isa(std::string_view name);

// The widest instruction set both the CPU and the operating system support (cpuid and xgetbv, through
// the compiler's __builtin_cpu_supports).
Isa cpu_isa();
// cpu_isa(), lowered by the environment variable TWINRAY_ISA when it is set. Throws std::invalid_argument
// naming the variable when its value is unknown or above what the CPU supports.
Isa selected_isa();
// Every instruction set this CPU can run, narrowest first (for tests that compare all paths).
std::vector<Isa> runnable_isas();

}  // namespace twinray
