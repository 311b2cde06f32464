#!/usr/bin/env bash
# Render efficiency of twinray against Mitsuba 3 (issue 13): time x relMSE of both renderers on the Cornell
# box and on the mirror-and-glass box, measured back to back in the same run, repeated, medians printed.
#
#   bash scripts/bench-mitsuba.sh [REPEATS] [SPP]      defaults: 3 repetitions, 256 spp, 2 threads
#
# Each repetition is one `twinray compare SCENE --peer mitsuba --spp SPP --batches 2 --threads 2`: twinray
# (the default backend, bvh8, and the default sampler) and then Mitsuba (llvm_ad_rgb when it works, else
# scalar_rgb; the variant is printed) render the same exported scene. relMSE is the noise-based estimate of each render
# (harness/compare/image_comparison.h: the variance of the mean from the two independent batches over
# (mean^2 + 0.01), averaged over pixels and channels), which needs no reference and carries no reference
# noise; it equals the relMSE against the truth when the verdict is "agree" (no bias). For the Cornell box
# the relMSE against Mitsuba's 4096-spp reference ($TWINRAY_SHARED/references/cornell-box) is printed too.
# Times are render times (no scene loading or BVH build; Mitsuba's kernel compilation is done in an untimed
# warm-up render). Efficiency = seconds x relMSE, lower is better; the ratio is twinray's over Mitsuba's
# (the goal: at most 0.5).
#
# TWINRAY_CAUSTICS=off renders twinray without caustic light tracing (compare --caustics; default auto),
# TWINRAY_SPLITS=K with K path continuations from each first non-delta vertex (compare --splits; default
# render's), and TWINRAY_LIGHT_CONNECTIONS=M with M light subpaths joined to the camera paths (compare
# --light-connections; default render's), for a before/after with one build.
#
# Needs Mitsuba (bash scripts/setup-mitsuba.sh) and a Release build (build/, or $TWINRAY_BUILD_DIR). The
# machine is shared: the script prints the CPU and the load average, and the medians absorb some noise.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${TWINRAY_BUILD_DIR:-$root/build}"
repeats="${1:-3}"
spp="${2:-256}"
twinray="$build/cli/twinray"
[ -x "$twinray" ] || { echo "bench-mitsuba: $twinray not built (bash scripts/setup.sh)" >&2; exit 2; }
if [ -z "${TWINRAY_SHARED:-}" ] && [ -d "$root/../shared" ]; then
  export TWINRAY_SHARED="$(cd "$root/../shared" && pwd)"
fi
out="${TWINRAY_BENCH_OUT:-$root/out/bench-mitsuba}"
mkdir -p "$out"

echo "bench-mitsuba: $(lscpu | grep 'Model name' | sed 's/  */ /g'), $(nproc) cores; load average $(cut -d' ' -f1-3 /proc/loadavg)"
echo "bench-mitsuba: $repeats repetitions of $spp spp, 2 threads, both renderers back to back, twinray --caustics ${TWINRAY_CAUSTICS:-auto}${TWINRAY_SPLITS:+ --splits $TWINRAY_SPLITS}${TWINRAY_LIGHT_CONNECTIONS:+ --light-connections $TWINRAY_LIGHT_CONNECTIONS}"
for scene in cornell-box-reference cornell-mirror-glass; do
  reference=()
  ref="${TWINRAY_SHARED:-}/references/cornell-box/mitsuba_ref.exr"
  if [ "$scene" = cornell-box-reference ] && [ -f "$ref" ]; then reference=(--reference "$ref"); fi
  for r in $(seq 1 "$repeats"); do
    "$twinray" compare "$root/scenes/$scene.json" --spp "$spp" --batches 2 --threads 2 --seed "$r" \
      --caustics "${TWINRAY_CAUSTICS:-auto}" ${TWINRAY_SPLITS:+--splits "$TWINRAY_SPLITS"} \
      ${TWINRAY_LIGHT_CONNECTIONS:+--light-connections "$TWINRAY_LIGHT_CONNECTIONS"} \
      "${reference[@]}" --out "$out/$scene-$r" >"$out/$scene-$r.log" 2>&1 || {
      rc=$?
      # Exit 1 is a "differ" verdict: still a measurement, reported below.
      [ "$rc" -eq 1 ] || { cat "$out/$scene-$r.log" >&2; exit "$rc"; }
    }
    echo "bench-mitsuba: $scene run $r done ($(grep -E '^verdict' "$out/$scene-$r.log" | sed 's/verdict *//'))"
  done
done

python3 - "$out" "$repeats" <<'PY'
import json, statistics, sys
out, repeats = sys.argv[1], int(sys.argv[2])
print()
print(f"{'scene':<24} {'renderer':<22} {'seconds':>8} {'relMSE':>11} {'vs ref':>11} {'time x relMSE':>14}")
for scene in ("cornell-box-reference", "cornell-mirror-glass"):
    runs = [json.load(open(f"{out}/{scene}-{r}/compare.json")) for r in range(1, repeats + 1)]
    eff = {}
    for name in ("twinray", "mitsuba"):
        rs = [run["renderers"][name] for run in runs]
        sec = statistics.median(x["seconds"] for x in rs)
        noise = statistics.median(x["relmse_from_noise"] for x in rs)
        vs_ref = statistics.median(x["relmse"] for x in rs) if runs[0]["reference"] else None
        eff[name] = statistics.median(x["seconds"] * x["relmse_from_noise"] for x in rs)
        label = f"{name} ({rs[0]['variant']})"
        ref_text = f"{vs_ref:11.4e}" if vs_ref is not None else f"{'-':>11}"
        print(f"{scene:<24} {label:<22} {sec:8.2f} {noise:11.4e} {ref_text} {eff[name]:14.4e}")
    verdicts = ", ".join(run["verdict"] for run in runs)
    print(f"{scene:<24} ratio twinray / mitsuba = {eff['twinray'] / eff['mitsuba']:.3f}   (verdicts: {verdicts})")
PY
