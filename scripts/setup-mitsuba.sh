#!/usr/bin/env bash
# Installs Mitsuba 3 (the peer renderer of `twinray compare` and `converge --peer mitsuba`) into a Python
# virtual environment of its own, and Debian's LLVM 19, which Mitsuba's vectorised llvm_* variants load at run
# time (Debian's LLVM 14 and 15 fail in them with an instruction-selection error).
#
#   bash scripts/setup-mitsuba.sh        idempotent: returns at once when everything is in place
#
# The environment lives in the twinray cache folder, shared by every checkout of the repository:
# $TWINRAY_CACHE_DIR, else $XDG_CACHE_HOME/twinray, else ~/.cache/twinray, subfolder mitsuba-venv/ (the same
# rule as the reference cache, harness/converge/reference_cache.h). TWINRAY_MITSUBA_VENV overrides the
# folder. twinray finds it there by itself; scripts/mitsuba_render.py runs inside it.
#
# Not part of scripts/test.sh (the packages are ~150 MB to download, and the tests that need Mitsuba skip with
# a message naming this script when it is absent, docs/mitsuba.md); .ci/run calls it before the suites.
set -euo pipefail

MITSUBA_VERSION=3.9.1
cache="${TWINRAY_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/twinray}"
venv="${TWINRAY_MITSUBA_VENV:-$cache/mitsuba-venv}"

# LLVM 19 from Debian 12's archive (libLLVM.so.19.1): only the llvm_* variants need it; scalar_rgb works
# without it.
# python3-venv: Debian's python3 creates virtual environments only with it.
installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
if ! installed libllvm19 || ! installed python3-venv; then
  echo "setup-mitsuba: installing libllvm19 and python3-venv" >&2
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends python3-venv >/dev/null
  $SUDO apt-get install -y -qq --no-install-recommends libllvm19 >/dev/null || \
    echo "setup-mitsuba: libllvm19 could not be installed: only the scalar_rgb variant will work" >&2
fi

if [ -x "$venv/bin/python" ] && "$venv/bin/python" -c "import mitsuba, sys; sys.exit(mitsuba.__version__ != '$MITSUBA_VERSION')" 2>/dev/null; then
  exit 0
fi

echo "setup-mitsuba: creating $venv with mitsuba==$MITSUBA_VERSION" >&2
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --upgrade pip
"$venv/bin/python" -m pip install --quiet "mitsuba==$MITSUBA_VERSION" numpy
"$venv/bin/python" -c "import mitsuba; print('setup-mitsuba: mitsuba', mitsuba.__version__, 'in $venv')"
