#!/usr/bin/env bash
# Install what the tests use besides cargo, inside the project (but chromium, from apt):
#   tools/node/node_modules  the Khronos glTF-Validator, gltfpack, glTF-Transform, three.js (npm)
#   .venv                    python with numpy + scipy (the peer reference), usd-core, jsonschema
#   .venv-bpy                Blender as a Python module (bpy 5.0.1 needs Python 3.11; it pins
#                            numpy 1.26, hence a venv of its own) for the USD import test
#   chromium                 (apt, system-wide) for the three.js playback test
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
if [ ! -x .venv-bpy/bin/python ] || ! .venv-bpy/bin/python -c "import bpy" 2>/dev/null; then
  if ! command -v python3.11 >/dev/null 2>&1; then
    echo "setup: bpy (Blender 5.0 as a Python module) needs python3.11, which is not on PATH; install it and run again" >&2
    exit 1
  fi
  echo "setup: creating .venv-bpy with bpy 5.0.1 (pip, about 400 MB to download)"
  python3.11 -m venv .venv-bpy
  .venv-bpy/bin/pip install --quiet --disable-pip-version-check -r tools/requirements-bpy.txt
fi
# Chromium (Debian package) plays outputs through three.js in tests/browser.rs (WebGL2 on
# SwiftShader, no GPU). The one system-wide install: apt needs root (or sudo).
if ! command -v chromium >/dev/null 2>&1; then
  echo "setup: installing chromium (apt)"
  if [ "$(id -u)" = 0 ]; then SUDO=""; else SUDO="sudo"; fi
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium >/dev/null 2>&1 \
    || { $SUDO apt-get update -q >/dev/null 2>&1 && $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium >/dev/null; } \
    || { echo "setup: could not install chromium with apt-get (it needs root or sudo); install the Debian package chromium and run again" >&2; exit 1; }
fi
