#!/usr/bin/env bash
# Fuzzes the input loaders with libFuzzer (clang from Debian) under AddressSanitizer + UBSan.
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]     SECONDS per target (default 60); targets default to all of
#                                              fuzz_scene_json fuzz_obj fuzz_ply, run one after the other.
#
# Builds in build-fuzz/ (TWINRAY_FUZZ_BUILD_DIR overrides), separate from the Release build. The seed corpus
# is made afresh on every run from scenes/*.json and small meshes written below (no binary blobs in the
# repository); what the fuzzer discovers accumulates in build-fuzz/corpus/TARGET and is reused next time.
# A crash, sanitizer report, leak, timeout (> 10 s for one input) or out-of-memory (> 2 GiB) leaves its
# input in build-fuzz/artifacts/TARGET/ and makes the script exit 1.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${TWINRAY_FUZZ_BUILD_DIR:-$root/build-fuzz}"
seconds="${1:-60}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_scene_json fuzz_obj fuzz_ply)

if ! command -v clang++-14 >/dev/null ||
   ! ls /usr/lib/llvm-14/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1; then
  echo "fuzz.sh: installing clang-14 and libclang-rt-14-dev"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq clang-14 libclang-rt-14-dev >/dev/null
fi

cmake -S "$root" -B "$build" -G Ninja -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTWINRAY_FUZZ=ON -DTWINRAY_SANITIZE=address,undefined \
  -DTWINRAY_BUILD_TESTS=OFF -DTWINRAY_BUILD_BENCH=OFF >/dev/null
cmake --build "$build" -j "${TWINRAY_FUZZ_JOBS:-2}" --target "${targets[@]}"

# --- seed corpus, made at run time -------------------------------------------------------------------
seeds="$build/seeds"
rm -rf "$seeds"
mkdir -p "$seeds/fuzz_scene_json" "$seeds/fuzz_obj" "$seeds/fuzz_ply"
cp "$root"/scenes/*.json "$seeds/fuzz_scene_json/"
# Scenes that reference the two meshes the fuzz target provides next to its scene file.
cat >"$seeds/fuzz_scene_json/meshes.json" <<'JSON'
{"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40, "width": 8, "height": 8},
 "materials": {"w": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}, "l": {"type": "emissive", "radiance": [4, 4, 4]}},
 "shapes": [{"type": "mesh", "file": "tri.obj", "material": "w", "transform": [{"translate": [1, 0, 0]}, {"rotate": {"axis": [0, 1, 0], "angle": 30}}, {"scale": 2}]},
            {"type": "mesh", "file": "tri.ply", "material": "l"},
            {"type": "mesh", "positions": [0, 0, 0, 1, 0, 0, 0, 1, 0], "indices": [0, 1, 2], "material": "w"},
            {"type": "sphere", "center": [0, 0, 0], "radius": 0.5, "material": "w"}],
 "environment": {"type": "constant", "radiance": [1, 1, 1]},
 "render": {"spp": 4, "max_depth": 3, "seed": 7}}
JSON
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n' >"$seeds/fuzz_obj/quad.obj"
printf '# tetrahedron\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\nf 1/1/1 3/1/1 2/1/1\nf 1//1 2//1 4//1\nf -4 -1 -2\nf 2 3 4\n' >"$seeds/fuzz_obj/tet.obj"
printf 'o a\ng b\nusemtl m\ns off\nv 1e-30 -2.5e+3 .5\nv 1 2 3 1.0\nv 4 5 6\nl 1 2\np 1\nf 1 2 3\n' >"$seeds/fuzz_obj/misc.obj"
ply_head='ply\nformat %s 1.0\ncomment seed\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face 2\nproperty list uchar int vertex_indices\nelement edge 1\nproperty list uchar int vertex_pair\nend_header\n'
printf "$ply_head" ascii >"$seeds/fuzz_ply/quad_ascii.ply"
printf '0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n3 0 1 2\n4 0 1 2 3\n2 0 1\n' >>"$seeds/fuzz_ply/quad_ascii.ply"
python3 - "$seeds/fuzz_ply" "$ply_head" <<'PY'
import struct, sys
out, head = sys.argv[1], sys.argv[2].replace('\\n', '\n')
verts = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
for name, fmt, e in (("binary_little_endian", "quad_le.ply", "<"), ("binary_big_endian", "quad_be.ply", ">")):
    body = b"".join(struct.pack(e + "fffB", *v, 7) for v in verts)
    body += struct.pack(e + "Biii", 3, 0, 1, 2) + struct.pack(e + "Biiii", 4, 0, 1, 2, 3)
    body += struct.pack(e + "Bii", 2, 0, 1)
    open(f"{out}/{fmt}", "wb").write((head % name).encode() + body)
PY
# A dictionary of the scene format's keywords helps the JSON fuzzer past the validator's key checks.
dict="$build/scene_json.dict"
: >"$dict"
for word in camera materials shapes environment render type mesh sphere file positions indices material \
            center radius transform translate rotate scale axis angle matrix position look_at up fov width height \
            diffuse mirror glass emissive albedo reflectance ior radiance constant image rotation spp max_depth seed \
            name comment; do
  printf '"\\"%s\\""\n' "$word" >>"$dict"
done

# --- run ---------------------------------------------------------------------------------------------
status=0
for target in "${targets[@]}"; do
  corpus="$build/corpus/$target"
  artifacts="$build/artifacts/$target/"
  mkdir -p "$corpus" "$artifacts"
  extra=()
  [ "$target" = fuzz_scene_json ] && extra=(-dict="$dict")
  echo "fuzz.sh: $target for ${seconds} s"
  log="$build/$target.log"
  if ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
     "$build/fuzz/$target" "$corpus" "$seeds/$target" "${extra[@]}" -max_total_time="$seconds" -timeout=10 \
       -rss_limit_mb=2048 -max_len=65536 -artifact_prefix="$artifacts" -print_final_stats=1 >"$log" 2>&1; then
    grep -E '^stat::number_of_executed_units|^Done' "$log" | tr '\n' ' '; echo
  else
    status=1
    echo "fuzz.sh: $target FAILED (input in $artifacts):"
    tail -n 40 "$log"
  fi
done
exit $status
