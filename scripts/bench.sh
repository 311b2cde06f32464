#!/usr/bin/env bash
# One command from a fresh machine to the benchmark report (docs/benchmarks.md):
#   1. set-up: Debian packages (incl. gnuplot-nox for the plots) and a Release build (scripts/setup.sh);
#   2. twinray_bench: build and traversal benchmarks of bvh, embree, embree-fast (and brute on the 1k
#      scenes) over the procedural scale series and the shared meshes -> bench.json (Google Benchmark JSON);
#   3. twinray converge on the Cornell box: error against time for bvh and embree-fast, MIS / BSDF / light
#      sampling (reference rendered once with embree and cached, see docs/benchmarks.md);
#   4. twinray report: report.html + report.md with tables, plots and traversal-cost heatmaps.
# About 12 minutes on the 2-core reference machine from scratch (build ~5, benchmarks ~5, converge ~2).
#
# Knobs (environment): TWINRAY_OUT (default out/), TWINRAY_BUILD_DIR (default build/), TWINRAY_SHARED
# (default ../shared; meshes are left out when absent), BENCH_MIN_TIME (seconds per benchmark, default
# 0.05), BENCH_MAX_TRIANGLES (largest scale-series scene, default 1048576 = 1M; 4194304 adds the 4M scenes and about five minutes), CONVERGE_BUDGET (seconds per
# backend and strategy, default 6), CONVERGE_REFERENCE_SPP (default 512), BENCH_SCENES (comma-separated scene
# files of your own, .json / Mitsuba .xml / .obj / .ply, benchmarked beside the bundled ones and given a
# heatmap in the report).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${TWINRAY_BUILD_DIR:-$root/build}"
out="${TWINRAY_OUT:-$root/out}/bench"
min_time="${BENCH_MIN_TIME:-0.05}"
max_triangles="${BENCH_MAX_TRIANGLES:-1048576}"
budget="${CONVERGE_BUDGET:-6}"
reference_spp="${CONVERGE_REFERENCE_SPP:-512}"
user_scenes="${BENCH_SCENES:-}"

if [ -z "${TWINRAY_SHARED:-}" ] && [ -d "$root/../shared" ]; then
  export TWINRAY_SHARED="$(cd "$root/../shared" && pwd)"
fi

start=$(date +%s)
bash "$root/scripts/setup.sh"
if ! grep -q "TWINRAY_BUILD_BENCH:BOOL=ON" "$build/CMakeCache.txt"; then
  cmake -S "$root" -B "$build" -DTWINRAY_BUILD_BENCH=ON >/dev/null
  cmake --build "$build" --parallel "$(nproc)" --target twinray_bench
fi
echo "twinray bench: set-up and build took $(( $(date +%s) - start )) s" >&2
mkdir -p "$out"

"$build/bench/twinray_bench" \
  --twinray_max_triangles="$max_triangles" \
  ${user_scenes:+--twinray_scenes="$user_scenes"} \
  --benchmark_min_time="$min_time" \
  --benchmark_out="$out/bench.json" --benchmark_out_format=json \
  --benchmark_counters_tabular=false | tee "$out/bench.txt"
echo "twinray bench: benchmarks done at $(( $(date +%s) - start )) s" >&2

"$build/cli/twinray" converge "$root/scenes/cornell-box.json" \
  --backends bvh,embree-fast --strategies mis,bsdf,light \
  --reference-spp "$reference_spp" --budget "$budget" --out "$out/converge-cornell-box"
echo "twinray bench: converge done at $(( $(date +%s) - start )) s" >&2

heatmaps=(--heatmap "$root/scenes/cornell-box.json")
for mesh in stanford-bunny.obj dragon_100k.ply dabrovic_sponza.obj; do
  if [ -n "${TWINRAY_SHARED:-}" ] && [ -f "$TWINRAY_SHARED/data/meshes/$mesh" ]; then
    heatmaps+=(--heatmap "$TWINRAY_SHARED/data/meshes/$mesh")
  fi
done
IFS=',' read -r -a user_scene_list <<< "$user_scenes"
for scene in "${user_scene_list[@]}"; do heatmaps+=(--heatmap "$scene"); done
"$build/cli/twinray" report --bench "$out/bench.json" --converge "$out/converge-cornell-box" "${heatmaps[@]}" \
  --out "$out/report"
echo "twinray bench: report at $out/report/report.html ($(( $(date +%s) - start )) s in all)" >&2
