#!/usr/bin/env bash
# Install what the tests use besides cargo, inside the project (nothing system-wide):
#   tools/validator/node_modules  the Khronos glTF-Validator (npm package gltf-validator)
#   .venv                         python with numpy + scipy (the peer reference) and usd-core
# Safe to run again: it only installs what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -f tools/validator/node_modules/gltf-validator/package.json ]; then
  echo "setup: installing gltf-validator (npm)"
  (cd tools/validator && npm install --no-audit --no-fund --loglevel=error)
fi
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import numpy, scipy, pxr, jsonschema" 2>/dev/null; then
  echo "setup: creating .venv with numpy, scipy, usd-core, jsonschema (pip)"
  python3 -m venv .venv
  .venv/bin/pip install --quiet --disable-pip-version-check -r tools/requirements.txt
fi
