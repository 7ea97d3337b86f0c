#!/usr/bin/env bash
# Every test: installs the test tools (validator, python venv) if missing, then runs the suite
# with them required (a missing tool fails the run instead of skipping).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-tools.sh
export INBETWEEN_REQUIRE_TOOLS=1
cargo test --release --all-targets "$@"
