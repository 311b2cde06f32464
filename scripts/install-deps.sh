#!/usr/bin/env bash
# Installs twinray's build dependencies from Debian 12's archive. Idempotent: when every package
# is already installed it returns at once without touching apt.
set -euo pipefail

PACKAGES=(
  cmake ninja-build g++ pkg-config
  libembree-dev          # Embree 3.13.5: the reference backend
  libtbb-dev             # oneTBB: parallel build and render
  libopenimageio-dev     # image I/O (EXR, PNG, HDR)
  libopenexr-dev
  libglm-dev
  libgtest-dev libgmock-dev
  libbenchmark-dev
  gnuplot-nox            # plots of the benchmark and convergence reports (SVG, no X)
  nlohmann-json3-dev     # scene format
  libcli11-dev           # command line
  libfmt-dev
  libpugixml-dev         # XML: Mitsuba 3 scenes (twinray export, .xml scenes)
  libseccomp-dev         # the plugin worker's system-call sandbox (backends/plugin/worker)
  libgmp-dev             # exact rational arithmetic (GMP, gmpxx): the exact backend and the arbiter
  libmpfr-dev            # correctly rounded conversion of exact values to float (MPFR)
  libxml2-utils          # xmllint: the tests validate twinray grade's JUnit XML against an XSD
  python3-jsonschema     # the tests validate twinray grade's Gradescope results.json against a JSON schema
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "twinray: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
