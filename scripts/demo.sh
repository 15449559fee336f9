#!/usr/bin/env bash
# Render the bundled Stanford bunny in marble (see README.md). Usage: scripts/demo.sh [BUILD_DIR]
set -euo pipefail
build=${1:-build}
mkdir -p out
exec xvfb-run -a -s "-screen 0 1024x768x24" "$build/bin/translucency" render \
  --mesh Data/bunny.ply --target-tets 200000 --material marble \
  --light directional:0,-1,-1:1 --light uniform:0.1 \
  --output out/demo --png out/demo.png --slice-png out/demo_slice.png --json out/demo.json
