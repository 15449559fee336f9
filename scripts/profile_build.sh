#!/usr/bin/env bash
# Where a cold build's CPU goes (Documentation/Building.md).
# Usage: scripts/profile_build.sh BUILD_DIR [TARGET] [CMAKE_ARG...]
#   BUILD_DIR  a fresh build tree (must not exist: the point is a cold build)
#   TARGET     default TranslucencyDemo (what `make demo` builds); "all" for `make build`
# Configures like `make configure`, with ccache off and every compile, link and
# custom command timed (cmake/TranslucencyBuildTiming.cmake), builds TARGET with
# JOBS (default 2) jobs under `nice -n 10`, then prints scripts/build_profile.py's
# tables. Files in BUILD_DIR: build-steps.log (one line per step), build.time
# (user, sys, wall seconds of the whole build), configure.time (the same for the
# configure step), load.txt (uptime before and after).
set -euo pipefail
dir=${1:?usage: scripts/profile_build.sh BUILD_DIR [TARGET] [CMAKE_ARG...]}
target=${2:-TranslucencyDemo}
shift $(( $# >= 2 ? 2 : 1 ))
jobs=${JOBS:-2}
here=$(cd "$(dirname "$0")/.." && pwd)
if [ -e "$dir" ]; then
  echo "profile_build: $dir exists; a cold build needs a fresh tree" >&2
  exit 2
fi
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
export CCACHE_DISABLE=1
uptime > "$dir/load.txt"
/usr/bin/time -o "$dir/configure.time" -f "%U %S %e" \
  make -C "$here" --no-print-directory configure BUILD_DIR="$dir" \
  CMAKE_ARGS="-DCMAKE_PROJECT_INCLUDE=$here/cmake/TranslucencyBuildTiming.cmake -DTRANSLUCENCY_BUILD_TIMING_LOG=$dir/build-steps.log $*" \
  > "$dir/configure.out"
/usr/bin/time -o "$dir/build.time" -f "%U %S %e" \
  nice -n 10 cmake --build "$dir" -j "$jobs" --target "$target" > "$dir/build.out"
uptime >> "$dir/load.txt"
/usr/bin/python3 "$here/scripts/build_profile.py" "$dir/build-steps.log" --total "$dir/build.time"
echo "configure (user sys wall s): $(cat "$dir/configure.time")"
cat "$dir/load.txt"
