#!/usr/bin/env bash
# Install what the tests use besides cargo, inside the project (nothing system-wide):
#   tools/node/node_modules  the Khronos glTF-Validator, gltfpack and glTF-Transform (npm)
#   .venv                    python with numpy + scipy (the peer reference), usd-core, jsonschema
# Safe to run again: it only installs what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! (cd tools/node && node -e "const fs = require('fs'); for (const p of Object.keys(require('./package.json').dependencies)) fs.accessSync('node_modules/' + p + '/package.json')") 2>/dev/null; then
  echo "setup: installing the node tools (npm: gltf-validator, gltfpack, @gltf-transform/cli)"
  (cd tools/node && npm install --no-audit --no-fund --loglevel=error)
fi
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import numpy, scipy, pxr, jsonschema" 2>/dev/null; then
  echo "setup: creating .venv with numpy, scipy, usd-core, jsonschema (pip)"
  python3 -m venv .venv
  .venv/bin/pip install --quiet --disable-pip-version-check -r tools/requirements.txt
fi
