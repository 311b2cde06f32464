#!/usr/bin/env bash
# Configures and builds the instrumented tree shared by scripts/sanitize.sh and scripts/fuzz.sh:
#
#   scripts/configure-asan.sh [ninja targets...]     (default: everything)
#
# One build serves both, so CI compiles the sources once, not twice: clang 14 with AddressSanitizer +
# UndefinedBehaviorSanitizer (-fno-sanitize-recover=all: any report aborts) and libFuzzer's coverage
# instrumentation (-fsanitize=fuzzer-no-link, which costs the test programs nothing but a few counters;
# only the fuzz targets link the fuzzer itself). Why clang for the sanitizer suite too: libFuzzer needs it
# anyway, and with -O1 -gline-tables-only it builds the whole tree in about 4.5 minutes on 2 cores.
# -O1 keeps the suite fast (2.5 minutes under ASan); line tables give reports file:line without full
# debug info. No benchmarks. Builds in build-asan/ (TWINRAY_ASAN_BUILD_DIR overrides).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${TWINRAY_ASAN_BUILD_DIR:-$root/build-asan}"

bash "$root/scripts/install-deps.sh"
bash "$root/scripts/install-clang.sh"

if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only -DNDEBUG" \
    -DTWINRAY_SANITIZE=address,undefined -DTWINRAY_FUZZ=ON -DTWINRAY_BUILD_BENCH=OFF >/dev/null
fi
jobs="${TWINRAY_ASAN_JOBS:-$(nproc)}"
if [ $# -gt 0 ]; then
  cmake --build "$build" --parallel "$jobs" --target "$@"
else
  cmake --build "$build" --parallel "$jobs"
fi
