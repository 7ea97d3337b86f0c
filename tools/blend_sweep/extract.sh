#!/usr/bin/env bash
# Extract Bandai Namco's walk, run, dash, walk-back, walk-left, walk-right and walk-turn captures
# (1,067 BVH files, 214 MB) from a git copy of
# github.com/BandaiNamcoResearchInc/Bandai-Namco-Research-Motiondataset into OUT, named
# dN_<motion>_<style>_NNN.bvh (N the dataset, 1 or 2).
# Usage: extract.sh GIT_DIR OUT
set -euo pipefail
git_dir=$1 out=$2
mkdir -p "$out"
git --git-dir="$git_dir" ls-tree -r --name-only HEAD |
  grep -E 'dataset-[12]_(walk|run|dash|walk-back|walk-left|walk-right|walk-turn-left|walk-turn-right)_[a-z-]*_[0-9]*\.bvh$' |
  while read -r path; do
    name=$(basename "$path" | sed -E 's/^dataset-([12])_/d\1_/')
    git --git-dir="$git_dir" show "HEAD:$path" > "$out/$name"
  done
ls "$out" | wc -l
