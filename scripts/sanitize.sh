#!/usr/bin/env bash
# Builds the whole project and its test suite with AddressSanitizer + UndefinedBehaviorSanitizer and runs
# every test with ctest. Any sanitizer report aborts the test that triggered it (-fno-sanitize-recover=all,
# halt_on_error, abort_on_error), so a clean run means no report at all.
#
#   scripts/sanitize.sh [ctest arguments...]
#
# The instrumented tree (clang 14, build-asan/) is made by scripts/configure-asan.sh and shared with
# scripts/fuzz.sh. Embree and oneTBB come from Debian and are not instrumented: ASan still checks every
# access our code makes, including into buffers we hand to Embree, but not Embree's own accesses.
# scripts/lsan.supp lists the only suppressions, each with its reason.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${TWINRAY_ASAN_BUILD_DIR:-$root/build-asan}"

bash "$root/scripts/configure-asan.sh"

if [ -z "${TWINRAY_SHARED:-}" ] && [ -d "$root/../shared" ]; then
  export TWINRAY_SHARED="$(cd "$root/../shared" && pwd)"
fi
# detect_leaks: on, with the suppressions below. strict_string_checks and detect_stack_use_after_return
# widen what is checked. abort_on_error gives a core-style exit that ctest reports as a failure.
export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:abort_on_error=1:check_initialization_order=1"
export LSAN_OPTIONS="suppressions=$root/scripts/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
cd "$build"
ctest --output-on-failure --parallel "$(nproc)" --timeout 1200 "$@"
