#!/usr/bin/env bash
# Install the Debian packages Translucency needs, only those that are missing.
# Idempotent: a second run installs nothing. Needs root (or sudo) on Debian 12.
set -euo pipefail

packages=(
  clang-14 libclang-rt-14-dev libomp-14-dev
  cmake g++ make ccache
  paraview-dev python3-paraview
  mpi-default-dev libdouble-conversion-dev
  libtet1.5-dev libeigen3-dev libglew-dev
  googletest libgtest-dev libbenchmark-dev
  xvfb xauth x11-apps libx11-dev libcli11-dev libqt5svg5 strace
  libsuitesparse-dev libhypre-dev libopenblas0-pthread python3-matplotlib
  libgmsh-dev libembree-dev
  qtxmlpatterns5-dev-tools qhelpgenerator-qt5 qttools5-dev
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
# Never libvtk9-dev / python3-vtk9: they conflict with python3-paraview.
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
