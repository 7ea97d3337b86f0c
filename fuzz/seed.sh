#!/usr/bin/env bash
# Seed the fuzz corpora with the project's samples and the real-file fixtures
# (../shared/fixtures), then run a target:   bash fuzz/seed.sh && cd fuzz &&
#   cargo +nightly fuzz run gltf_read -- -max_total_time=1800 -rss_limit_mb=2048
set -euo pipefail
cd "$(dirname "$0")"
F=../../shared/fixtures
mkdir -p corpus/{gltf_read,keyframes,blend,bvh,usd_stage,tween_write}
for t in gltf_read keyframes usd_stage tween_write; do
  cp ../samples/*.glb corpus/$t/
  [ -d $F ] && cp $F/morph-keyframes/*.glb $F/morph-khronos/SimpleMorph/glTF-Embedded/*.gltf \
    $F/morph-khronos/MorphStressTest/glTF-Embedded-bevy/*.gltf corpus/$t/ || true
done
[ -d $F ] && cp $F/skinned/*.glb corpus/blend/ && cp $F/skinned/*.glb corpus/gltf_read/ && cp $F/skinned/*.glb corpus/usd_stage/ || true
[ -d $F ] && cp $F/bvh/*.bvh corpus/bvh/ || true
# Cameras and lights (the USD stage writes them as Camera and UsdLux prims).
cat > corpus/usd_stage/lit.gltf <<'GLTF'
{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2, 3]}],
 "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "aspectRatio": 1.5, "znear": 0.1}},
  {"type": "orthographic", "orthographic": {"xmag": 2, "ymag": 1, "znear": 0, "zfar": 100}}],
 "extensionsUsed": ["KHR_lights_punctual"],
 "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 20, "range": 8},
  {"type": "spot", "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.6}}, {"type": "directional"}]}},
 "nodes": [{"camera": 0}, {"camera": 1, "translation": [0, 10, 0]},
  {"extensions": {"KHR_lights_punctual": {"light": 0}}, "children": [3]},
  {"extensions": {"KHR_lights_punctual": {"light": 1}}}]}
GLTF
echo "corpora: $(for t in corpus/*; do echo -n "$(basename $t)=$(ls $t | wc -l) "; done)"
# The decoders: streams cut from compressed variants made by the real tools (when installed).
B=../tools/node/node_modules/.bin
mkdir -p corpus/decoders
if [ -x $B/gltfpack ] && [ -d $F ]; then
  tmp=$(mktemp -d)
  $B/gltfpack -i $F/morph-keyframes/Flamingo.glb -o $tmp/cc.glb -cc >/dev/null 2>&1 || true
  $B/gltf-transform draco $F/morph-keyframes/Flamingo.glb $tmp/draco.glb >/dev/null 2>&1 || true
  # WebP textures (the USD stage writes them as PNG).
  $B/gltf-transform webp $F/morph-khronos/MorphStressTest/glTF/MorphStressTest.gltf \
    corpus/usd_stage/webp.glb >/dev/null 2>&1 || true
  cp $tmp/*.glb corpus/gltf_read/ 2>/dev/null || true
  # Raw streams with a 4-byte header choosing the decoder (see fuzz_targets/decoders.rs).
  python3 - "$tmp" corpus/decoders <<'PY'
import json, struct, sys, os
src, dst = sys.argv[1], sys.argv[2]
for name in ("cc.glb", "draco.glb"):
    p = os.path.join(src, name)
    if not os.path.exists(p): continue
    b = open(p, "rb").read(); n = struct.unpack("<I", b[12:16])[0]; j = json.loads(b[20:20+n]); bin0 = b[28+n:]
    for i, v in enumerate(j.get("bufferViews", [])):
        e = v.get("extensions", {}).get("EXT_meshopt_compression")
        if e:
            s = bin0[e.get("byteOffset", 0):e.get("byteOffset", 0) + e["byteLength"]]
            mode = ["ATTRIBUTES", "TRIANGLES", "INDICES"].index(e["mode"])
            open(os.path.join(dst, f"{name}-{i}"), "wb").write(bytes([mode, 0]) + struct.pack("<H", e["count"] % 4096) + s)
    for m in j.get("meshes", []):
        for pr in m["primitives"]:
            d = pr.get("extensions", {}).get("KHR_draco_mesh_compression")
            if d:
                v = j["bufferViews"][d["bufferView"]]; s = bin0[v.get("byteOffset", 0):v.get("byteOffset", 0) + v["byteLength"]]
                open(os.path.join(dst, f"{name}-draco"), "wb").write(bytes([3, 0, 0, 0]) + s)
PY
  rm -rf $tmp
fi
echo "decoders corpus: $(ls corpus/decoders | wc -l)"
