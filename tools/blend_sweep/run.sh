#!/usr/bin/env bash
# Blend every pair of LIST (from pairs.sh) with BIN at WEIGHTS (default 0.25,0.5,0.75), two at
# a time, leaving each pair's --report in OUT/A+B.json (the blends themselves are removed).
# Usage: run.sh BIN BN LIST OUT [WEIGHTS]
set -uo pipefail
export BIN=$1 BN=$2 OUT=$4 W=${5:-0.25,0.5,0.75}
mkdir -p "$OUT"
one() {
  local o="$OUT/$1+$2"
  "$BIN" blend "$BN/$1.bvh" "$BN/$2.bvh" --weight "$W" -o "$o.bvh" --report "$o.json" -q 2> "$o.err" ||
    echo "FAIL $1 $2: $(cat "$o.err")"
  rm -f "$o"*.bvh
}
export -f one
xargs -P 2 -L 1 bash -c 'one "$0" "$1"' < "$3"
