#!/usr/bin/env bash
# Fuzzes the input loaders with libFuzzer (clang 14 from Debian) under AddressSanitizer + UBSan.
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]     SECONDS of wall time (default 60); targets default to all of
#                                              fuzz_scene_json fuzz_scene_xml fuzz_obj fuzz_ply, which run concurrently
#                                              (TWINRAY_FUZZ_SEQUENTIAL=1 runs them one after the other).
#
# Uses the instrumented tree in build-asan/ (scripts/configure-asan.sh, shared with scripts/sanitize.sh;
# TWINRAY_ASAN_BUILD_DIR overrides). The seed corpus is made afresh on every run from scenes/*.json and
# small meshes written below (no binary blobs in the repository); what the fuzzer discovers accumulates in
# build-asan/corpus/TARGET and is reused next time. A crash, sanitizer report, leak, timeout (> 10 s for one
# input) or out-of-memory (> 2 GiB) leaves its input in build-asan/artifacts/TARGET/ and makes the script
# exit 1.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${TWINRAY_ASAN_BUILD_DIR:-$root/build-asan}"
seconds="${1:-60}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_scene_json fuzz_scene_xml fuzz_obj fuzz_ply)

bash "$root/scripts/configure-asan.sh" "${targets[@]}"

# --- seed corpus, made at run time -------------------------------------------------------------------
seeds="$build/seeds"
rm -rf "$seeds"
mkdir -p "$seeds/fuzz_scene_json" "$seeds/fuzz_scene_xml" "$seeds/fuzz_obj" "$seeds/fuzz_ply"
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
# Mitsuba XML: every supported element once, referencing the fuzz target's tri.obj and tri.ply.
cat >"$seeds/fuzz_scene_xml/all.xml" <<'XML'
<scene version="3.0.0">
  <default name="spp" value="4"/>
  <integrator type="path"><integer name="max_depth" value="-1"/><integer name="rr_depth" value="5"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/><string name="fov_axis" value="smaller"/>
    <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="$spp"/><integer name="seed" value="3"/></sampler>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film>
  </sensor>
  <bsdf type="twosided" id="w"><bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.6, 0.7"/></bsdf></bsdf>
  <bsdf type="conductor" id="m"><string name="material" value="none"/></bsdf>
  <bsdf type="dielectric" id="g"><float name="int_ior" value="1.5"/><string name="ext_ior" value="air"/></bsdf>
  <shape type="obj" id="a"><string name="filename" value="tri.obj"/><boolean name="face_normals" value="true"/><ref id="w"/>
    <transform name="to_world"><scale value="2"/><rotate y="1" angle="30"/><translate x="1"/></transform></shape>
  <shape type="ply"><string name="filename" value="tri.ply"/><boolean name="face_normals" value="true"/><boolean name="flip_normals" value="true"/>
    <bsdf type="diffuse"/><emitter type="area"><rgb name="radiance" value="4"/></emitter></shape>
  <shape type="sphere"><point name="center" value="0, 0, 0"/><float name="radius" value="0.5"/><ref id="g"/></shape>
  <shape type="rectangle"><ref id="m"/><transform name="to_world"><matrix value="1 0 0 0 0 1 0 0 0 0 1 -1 0 0 0 1"/></transform></shape>
  <shape type="cube"><ref id="w"/></shape>
  <emitter type="constant"><spectrum name="radiance" value="0.5"/></emitter>
</scene>
XML
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

# The XML fuzzer's dictionary: element, attribute and property names of the supported subset.
xml_dict="$build/scene_xml.dict"
: >"$xml_dict"
for word in '<scene' '<default' '<integrator' '<sensor' '<sampler' '<film' '<rfilter' '<bsdf' '<shape' '<emitter' \
            '<transform' '<lookat' '<translate' '<rotate' '<scale' '<matrix' '<float' '<integer' '<boolean' '<string' \
            '<rgb' '<spectrum' '<point' '<vector' '<ref' 'version=' 'type=' 'name=' 'value=' 'id=' 'origin=' 'target=' \
            'up=' 'angle=' '$spp' 'perspective' 'hdrfilm' 'box' 'independent' 'path' 'diffuse' 'conductor' 'dielectric' \
            'twosided' 'obj' 'ply' 'sphere' 'rectangle' 'cube' 'area' 'constant' 'envmap' 'to_world' 'filename' \
            'face_normals' 'flip_normals' 'reflectance' 'radiance' 'int_ior' 'ext_ior' 'fov' 'fov_axis' 'max_depth' \
            'sample_count' 'width' 'height' 'center' 'radius' 'tri.obj' 'tri.ply' 'true' 'false' '/>' '</'; do
  printf '"%s"\n' "${word//\"/\\\"}" >>"$xml_dict"
done

# --- run ---------------------------------------------------------------------------------------------
# Runs one target; its log goes to build-asan/TARGET.log, its verdict to build-asan/TARGET.status.
run_target() {
  local target="$1"
  local corpus="$build/corpus/$target" artifacts="$build/artifacts/$target/" log="$build/$target.log"
  mkdir -p "$corpus" "$artifacts"
  local extra=()
  [ "$target" = fuzz_scene_json ] && extra=(-dict="$dict")
  [ "$target" = fuzz_scene_xml ] && extra=(-dict="$xml_dict")
  if ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
     "$build/fuzz/$target" "$corpus" "$seeds/$target" "${extra[@]}" -max_total_time="$seconds" -timeout=10 \
       -rss_limit_mb=2048 -max_len=65536 -artifact_prefix="$artifacts" -print_final_stats=1 >"$log" 2>&1; then
    echo ok >"$build/$target.status"
  else
    echo failed >"$build/$target.status"
  fi
}

echo "fuzz.sh: ${targets[*]} for ${seconds} s$([ "${TWINRAY_FUZZ_SEQUENTIAL:-}" = 1 ] && echo ' each, one after the other' || echo ', concurrently')"
if [ "${TWINRAY_FUZZ_SEQUENTIAL:-}" = 1 ]; then
  for target in "${targets[@]}"; do run_target "$target"; done
else
  for target in "${targets[@]}"; do run_target "$target" & done
  wait
fi

status=0
for target in "${targets[@]}"; do
  log="$build/$target.log"
  if [ "$(cat "$build/$target.status")" = ok ]; then
    echo "fuzz.sh: $target: $(grep -E '^stat::number_of_executed_units' "$log" | tr -d '\n') $(grep -E '^Done' "$log" | tr -d '\n')"
  else
    status=1
    echo "fuzz.sh: $target FAILED (input in $build/artifacts/$target/):"
    tail -n 40 "$log"
  fi
done
exit $status
