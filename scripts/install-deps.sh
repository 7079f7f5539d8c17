#!/usr/bin/env bash
# Installs the Debian 12 packages Seiche builds with, and only those that are missing; package
# names given as arguments are installed too.
# Idempotent: a machine that has everything runs no apt-get at all.
set -euo pipefail

packages=(
  g++ cmake ninja-build ccache make
  libeigen3-dev libtbb-dev libxsimd-dev xtl-dev
  nlohmann-json3-dev libcli11-dev libfmt-dev libtinyobjloader-dev
  libgtest-dev libbenchmark-dev
  libopenvdb-dev libboost-iostreams-dev libblosc-dev
  python3 python3-matplotlib
  pybind11-dev python3-dev      # the Python module (python/), built by the normal build
  python3-numpy python3-pytest  # its tests (make test runs pytest through ctest)
  "$@"  # more, for other uses (install-ci-deps.sh: the AArch64 cross compiler, clang; make fuzz: clang;
        # make test: blender, for the Blender add-on's test)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "seiche: installing missing packages: ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "seiche: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  SUDO="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
