#!/usr/bin/env bash
# Write the sweeps' pair lists (one "A B" per line, capture names without .bvh) into OUT from
# the captures extract.sh put in BN:
#   walk_run  each style's walk_001 with its run_001 (15 styles of dataset 1, 7 of dataset 2)
#   cross     per dataset-1 style s and the next one t: walk_s_001 + walk_s_002, walk_s +
#             walk_t, walk_s + run_t, walk_s_002 + run_s
#   back_side walk-back, walk-left and walk-right of each dataset-1 style with the normal
#             style's, and each style's dash with its run
#   turning   each dataset-2 style's walk with its walk-turn-left and its walk-turn-right
#   self      each walk-turn capture with itself (run at weight 0.5 alone)
#   mixed     per dataset-1 style: walk + walk-back, walk-left + walk-right, walk + dash
# Usage: pairs.sh BN OUT
set -euo pipefail
bn=$1 out=$2
mkdir -p "$out"
styles1=$(cd "$bn" && ls d1_walk_*_001.bvh | sed -E 's/d1_walk_(.*)_001.bvh/\1/')
styles2=$(cd "$bn" && ls d2_walk_*_001.bvh | sed -E 's/d2_walk_(.*)_001.bvh/\1/')
read -r -a s1 <<< "$(echo $styles1)"
for f in walk_run cross back_side turning self mixed; do : > "$out/$f"; done
for s in $styles1; do echo "d1_walk_${s}_001 d1_run_${s}_001" >> "$out/walk_run"; done
for s in $styles2; do echo "d2_walk_${s}_001 d2_run_${s}_001" >> "$out/walk_run"; done
n=${#s1[@]}
for i in $(seq 0 $((n - 1))); do
  s=${s1[$i]} t=${s1[$(((i + 1) % n))]}
  {
    echo "d1_walk_${s}_001 d1_walk_${s}_002"
    echo "d1_walk_${s}_001 d1_walk_${t}_001"
    echo "d1_walk_${s}_001 d1_run_${t}_001"
    echo "d1_walk_${s}_002 d1_run_${s}_001"
  } >> "$out/cross"
  {
    echo "d1_walk_${s}_001 d1_walk-back_${s}_001"
    echo "d1_walk-left_${s}_001 d1_walk-right_${s}_001"
    echo "d1_walk_${s}_001 d1_dash_${s}_001"
  } >> "$out/mixed"
  for k in walk-back walk-left walk-right; do
    [ "$s" != normal ] && echo "d1_${k}_${s}_001 d1_${k}_normal_001" >> "$out/back_side"
  done
  echo "d1_dash_${s}_001 d1_run_${s}_001" >> "$out/back_side"
done
for s in $styles2; do
  for k in walk-turn-left walk-turn-right; do
    echo "d2_walk_${s}_001 d2_${k}_${s}_001" >> "$out/turning"
    echo "d2_${k}_${s}_001 d2_${k}_${s}_001" >> "$out/self"
  done
done
wc -l "$out"/*
