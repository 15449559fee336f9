#!/bin/sh
# The relight where the user meets it, GUI beside pvbatch (issue 31; the figure
# in Documentation/Performance.md, "ParaView pipeline").
#
#   OMP_NUM_THREADS=2 scripts/relight_gui_figure.sh build bunny1m.vtu [steps] [display]
#
# 1. pvbatch runs scripts/relight_gui_timing.py on the mesh (made from
#    Data/bunny.ply at 1M tets if the file does not exist), then
# 2. `paraview --dr --script=...` (the GUI, no user settings) under Xvfb on
#    display `display` (default 260) runs the same chain and relights on the
#    same file, and
# 3. the two JSON files are printed as one line each: cold chain, relight
#    median and every relight, in seconds, and the ratio GUI / pvbatch.
set -e
build=${1:?usage: relight_gui_figure.sh <build dir> <mesh.vtu> [steps] [display]}
mesh=${2:?usage: relight_gui_figure.sh <build dir> <mesh.vtu> [steps] [display]}
steps=${3:-5}
display=${4:-260}
here=$(cd "$(dirname "$0")" && pwd)
out=$(mktemp -d)
export TRANSLUCENCY_PLUGIN="$(cd "$build" && pwd)/lib/paraview-plugins/Translucency/Translucency.so"
export TRANSLUCENCY_SOURCE_DIR="$here/.." TRANSLUCENCY_RELIGHT_MESH="$mesh"
export TRANSLUCENCY_RELIGHT_STEPS="$steps" OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-passive}"
TRANSLUCENCY_RELIGHT_OUT="$out/pvbatch.json" pvbatch "$here/relight_gui_timing.py"
TRANSLUCENCY_RELIGHT_OUT="$out/gui.json" xvfb-run -n "$display" -a \
  -s "-noreset -screen 0 1280x1024x24" paraview --dr --script="$here/relight_gui_timing.py"
/usr/bin/python3 - "$out/pvbatch.json" "$out/gui.json" <<'EOF'
import json, sys
runs = [json.load(open(p)) for p in sys.argv[1:]]
for r in runs:
    if "error" in r:
        sys.exit(r["mode"] + ": " + r["error"])
    print("%-8s %d tets: cold %.3f s, relight median %.3f s (%s)" % (
        r["mode"], r["tets"], r["cold_seconds"], r["relight_median_seconds"],
        " ".join("%.3f" % s for s in r["relight_seconds"])))
print("GUI relight phases (medians, s): %s" % runs[1].get("relight_phase_median_seconds"))
print("GUI cold phases (s): %s" % runs[1].get("cold_phase_seconds"))
print("GUI / pvbatch: relight %.2f, cold %.2f" % (
    runs[1]["relight_median_seconds"] / runs[0]["relight_median_seconds"],
    runs[1]["cold_seconds"] / runs[0]["cold_seconds"]))
EOF
rm -rf "$out"
