#!/usr/bin/env bash
# Sets everything up and runs the main job on a bundled scene: renders the Cornell box with the SAH BVH
# backend and cross-checks the BVH against Embree on the same scene.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${TWINRAY_BUILD_DIR:-$root/build}"
out="${TWINRAY_OUT:-$root/out}"

bash "$root/scripts/setup.sh"
mkdir -p "$out"
"$build/cli/twinray" render "$root/scenes/cornell-box.json" --backend bvh --spp 64 -o "$out/cornell-box.exr" --png "$out/cornell-box.png"
"$build/cli/twinray" crosscheck "$root/scenes/cornell-box.json" --backends bvh,embree,brute --rays 20000
echo "twinray: image written to $out/cornell-box.png"
