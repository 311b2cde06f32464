#!/usr/bin/env bash
# Sets everything up (packages, Release build) and runs the whole test suite with ctest.
# Tests that need ../shared (real meshes, reference images) find it through TWINRAY_SHARED and skip with a
# message when it is absent; the core suite does not need it.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${TWINRAY_BUILD_DIR:-$root/build}"

bash "$root/scripts/setup.sh"

if [ -z "${TWINRAY_SHARED:-}" ] && [ -d "$root/../shared" ]; then
  export TWINRAY_SHARED="$(cd "$root/../shared" && pwd)"
fi
cd "$build"
ctest --output-on-failure --parallel "$(nproc)" "$@"
