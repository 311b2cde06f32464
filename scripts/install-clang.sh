#!/usr/bin/env bash
# Installs clang 14 and its runtime libraries (AddressSanitizer, UndefinedBehaviorSanitizer, libFuzzer) from
# Debian 12, for scripts/sanitize.sh and scripts/fuzz.sh. Idempotent: returns at once when they are present.
set -euo pipefail
if command -v clang++-14 >/dev/null &&
   ls /usr/lib/llvm-14/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1; then
  exit 0
fi
echo "install-clang.sh: installing clang-14 and libclang-rt-14-dev"
apt-get update -qq
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq clang-14 libclang-rt-14-dev >/dev/null
