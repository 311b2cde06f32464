#!/usr/bin/env python3
"""Renders a Mitsuba 3 XML scene for `twinray compare` and `twinray converge --peer mitsuba`.

Runs inside the virtual environment scripts/setup-mitsuba.sh creates. The image is rendered in BATCHES
independent batches (seeds SEED, SEED+1, ...) of equal sample count; the mean image is their average and
the per-pixel variance of that mean is the batches' sample variance divided by BATCHES, an estimate that
holds for any sampler. Writes:
  OUT            mean image, linear float RGB (OpenEXR)
  OUT.var.exr    per-pixel variance of the mean (RGB), when BATCHES >= 2
  JSON           {"variant", "mitsuba_version", "spp", "batches", "threads", "seconds", "load_seconds",
                  "warmup_seconds", "pass_seconds", "llvm"}
`seconds` is the wall time of the timed renders only: scene loading (which builds Mitsuba's acceleration
structure) and one untimed warm-up render (which compiles the LLVM kernels, cached for the timed ones) are
reported apart, as twinray's render time excludes its BVH build.

With --time S, batches of --spp samples are rendered until S seconds have passed (at least --batches of
them). With --sweep S (for `twinray converge --peer mitsuba`), one image per sample count 1, 2, 4, ... is
rendered (each after its own untimed warm-up, since the sample count is compiled into the kernel) until the
next one would take the total past S seconds or --max-spp is reached; OUT's stem gets "-SPP" per image and
the JSON lists {"spp", "seconds", "image"} under "points". Variant: --variant auto tries llvm_ad_rgb (needs LLVM 19: DRJIT_LIBLLVM_PATH, set here to Debian's
libLLVM.so.19.1 when unset) and falls back to scalar_rgb; the JSON says which ran.
"""
import argparse
import json
import os
import sys
import time

DEBIAN_LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"


def parse_args():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene")
    p.add_argument("--out", required=True)
    p.add_argument("--json", required=True)
    p.add_argument("--spp", type=int, default=64, help="samples per pixel (per batch with --time)")
    p.add_argument("--time", type=float, default=0.0, help="render batches until this many seconds")
    p.add_argument("--batches", type=int, default=8)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--threads", type=int, default=0, help="0 = all cores")
    p.add_argument("--variant", default="auto", help="auto, llvm_ad_rgb or scalar_rgb")
    p.add_argument("--sweep", type=float, default=0.0, help="error-against-time sweep with this budget (seconds)")
    p.add_argument("--max-spp", type=int, default=1 << 16)
    return p.parse_args()


def choose_variant(mi, wanted):
    if wanted != "auto":
        mi.set_variant(wanted)
        return wanted
    try:
        mi.set_variant("llvm_ad_rgb")
        # A tiny render makes Dr.Jit load LLVM and compile a kernel: this is where a missing or unusable LLVM fails.
        probe = mi.load_dict({"type": "scene", "sensor": {"type": "perspective", "film": {"type": "hdrfilm", "width": 2, "height": 2}},
                              "integrator": {"type": "path"}, "sphere": {"type": "sphere"},
                              "light": {"type": "constant"}})
        mi.render(probe, spp=1)
        return "llvm_ad_rgb"
    except Exception as e:  # noqa: BLE001 -- any failure means the vectorised variant is unusable here
        print(f"mitsuba_render: llvm_ad_rgb unavailable ({e}); using scalar_rgb", file=sys.stderr)
        mi.set_variant("scalar_rgb")
        return "scalar_rgb"


def main():
    args = parse_args()
    if args.spp < 1 or args.batches < 1:
        sys.exit("mitsuba_render: --spp and --batches must be at least 1")
    if os.path.exists(DEBIAN_LLVM):
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", DEBIAN_LLVM)
    import drjit as dr
    import mitsuba as mi
    import numpy as np

    variant = choose_variant(mi, args.variant)
    if args.threads > 0:
        dr.set_thread_count(args.threads)

    start = time.perf_counter()
    scene = mi.load_file(args.scene, spp=args.spp)
    load_seconds = time.perf_counter() - start

    def render(seed):
        img = mi.render(scene, spp=args.spp, seed=seed)
        arr = np.array(img, dtype=np.float64)  # forces evaluation
        return arr[:, :, :3]

    if args.sweep > 0.0:
        sweep(args, mi, dr, np, scene, variant, load_seconds)
        return

    start = time.perf_counter()
    render(args.seed + 0x7FFF0000)  # warm-up: kernel compilation, first-touch allocations; not in the image
    warmup_seconds = time.perf_counter() - start

    total = None
    total_sq = None
    pass_seconds = []
    batch = 0
    while True:
        t0 = time.perf_counter()
        img = render(args.seed + batch)
        pass_seconds.append(time.perf_counter() - t0)
        total = img if total is None else total + img
        total_sq = img * img if total_sq is None else total_sq + img * img
        batch += 1
        if batch >= args.batches and (args.time <= 0.0 or sum(pass_seconds) >= args.time):
            break
    n = float(batch)
    mean = total / n
    bitmap = mi.Bitmap(mean.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bitmap.write(args.out)
    if batch >= 2:
        var_of_mean = np.maximum(total_sq / n - mean * mean, 0.0) * n / (n - 1.0) / n
        root, _ = os.path.splitext(args.out)
        mi.Bitmap(var_of_mean.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB).write(root + ".var.exr")
    result = {
        "variant": variant,
        "mitsuba_version": mi.__version__,
        "spp": args.spp * batch,
        "batches": batch,
        "threads": dr.thread_count(),
        "seconds": sum(pass_seconds),
        "load_seconds": load_seconds,
        "warmup_seconds": warmup_seconds,
        "pass_seconds": pass_seconds,
        "llvm": os.environ.get("DRJIT_LIBLLVM_PATH", ""),
    }
    with open(args.json, "w") as f:
        json.dump(result, f, indent=2)
        f.write("\n")


def sweep(args, mi, dr, np, scene, variant, load_seconds):
    root, ext = os.path.splitext(args.out)
    points = []
    used = 0.0
    spp = 1
    while spp <= args.max_spp:
        if len(points) >= 2 and used + 2.0 * points[-1]["seconds"] > args.sweep:
            break
        np.array(mi.render(scene, spp=spp, seed=args.seed + 0x7FFF0000))  # warm-up: compiles this spp's kernel
        t0 = time.perf_counter()
        img = np.array(mi.render(scene, spp=spp, seed=args.seed), dtype=np.float32)[:, :, :3]
        seconds = time.perf_counter() - t0
        used += seconds
        path = f"{root}-{spp}{ext}"
        mi.Bitmap(img, pixel_format=mi.Bitmap.PixelFormat.RGB).write(path)
        points.append({"spp": spp, "seconds": seconds, "image": path})
        spp *= 2
    with open(args.json, "w") as f:
        json.dump({"variant": variant, "mitsuba_version": mi.__version__, "threads": dr.thread_count(),
                   "load_seconds": load_seconds, "points": points}, f, indent=2)
        f.write("\n")


if __name__ == "__main__":
    main()
