#!/usr/bin/env bash
# Render the bundled Stanford bunny in marble (see README.md), lit from the front
# (out/demo.png) and from behind (out/demo_backlit.png: only light that crossed the
# marble reaches the side we see, so the thin ears glow and the thick body stays
# dark; the second render re-uses the first one's tet mesh, out/demo.vtu).
# The mesh is gmsh's HXT (--mesher hxt): about half TetGen's time on the bunny
# at 200k tets, with better tets (Documentation/Performance.md, "End to end at
# 200k tets"). HXT's tet count differs slightly from one run to the next
# (about 0.2 %: Documentation/Pipeline.md, "Mesher").
# Usage: scripts/demo.sh [BUILD_DIR]
set -euo pipefail
build=${1:-build}
mkdir -p out
xvfb-run -a -s "-screen 0 1024x768x24" "$build/bin/translucency" render \
  --mesh Data/bunny.ply --target-tets 200000 --mesher hxt --material marble \
  --light directional:0,-1,-1:1 --light uniform:0.1 \
  --output out/demo --png out/demo.png --slice-png out/demo_slice.png --json out/demo.json
# The camera looks along -z (render's default --view 0,0,-1): a light travelling
# towards +z (and a little down) comes from behind the bunny.
exec xvfb-run -a -s "-screen 0 1024x768x24" "$build/bin/translucency" render \
  --mesh out/demo.vtu --material marble --light directional:0,-0.3,1:1 \
  --png out/demo_backlit.png --json out/demo_backlit.json
