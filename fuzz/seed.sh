#!/usr/bin/env bash
# Seed the fuzz corpora with the project's samples and the real-file fixtures
# (../shared/fixtures), then run a target:   bash fuzz/seed.sh && cd fuzz &&
#   cargo +nightly fuzz run gltf_read -- -max_total_time=1800 -rss_limit_mb=2048
set -euo pipefail
cd "$(dirname "$0")"
F=../../shared/fixtures
mkdir -p corpus/{gltf_read,keyframes,blend,bvh}
for t in gltf_read keyframes; do
  cp ../samples/*.glb corpus/$t/
  [ -d $F ] && cp $F/morph-keyframes/*.glb $F/morph-khronos/SimpleMorph/glTF-Embedded/*.gltf \
    $F/morph-khronos/MorphStressTest/glTF-Embedded-bevy/*.gltf corpus/$t/ || true
done
[ -d $F ] && cp $F/skinned/*.glb corpus/blend/ && cp $F/skinned/*.glb corpus/gltf_read/ || true
[ -d $F ] && cp $F/bvh/*.bvh corpus/bvh/ || true
echo "corpora: $(for t in corpus/*; do echo -n "$(basename $t)=$(ls $t | wc -l) "; done)"
