#!/usr/bin/env bash
# Every test: installs the test tools (validator, python venv) if missing, then runs the suite
# with them required (a missing tool fails the run instead of skipping).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-tools.sh
export INBETWEEN_REQUIRE_TOOLS=1
# Tests that skip part of their work (no ../shared/fixtures, say) write why here; printed last.
export INBETWEEN_SKIP_LOG="$PWD/target/skipped.log"
mkdir -p target && rm -f "$INBETWEEN_SKIP_LOG"
status=0
cargo test --release --all-targets "$@" || status=$?
if [ -s "$INBETWEEN_SKIP_LOG" ]; then
  echo "skipped ($(wc -l < "$INBETWEEN_SKIP_LOG") test parts):"
  sort "$INBETWEEN_SKIP_LOG" | sed 's/^/  /'
else
  echo "skipped: nothing"
fi
exit $status
