#!/usr/bin/env bash
# ctest's Blender.AddonImportsABakeAndRenders: bakes tests/data/blender_small.json (3 frames,
# a fluid block and a cloth) and tests/data/blender_bodies.json (4 frames, two rigid bodies: a
# box and an OBJ mesh) with seiche, then runs addon_test.py inside Blender, headless.
# Without Blender the test fails (it is not skipped): `make test` installs Debian's blender.
#   run_addon_test.sh SEICHE_EXE REPO WORK_DIR
set -euo pipefail
seiche=$1 repo=$2 work=$3
if ! command -v blender >/dev/null; then
  echo "FAIL: Blender is not installed, so the Blender add-on cannot be tested." >&2
  echo "      'make test' installs it (scripts/install-deps.sh blender), or: apt-get install blender" >&2
  exit 1
fi
rm -rf "$work"
mkdir -p "$work/out"
"$seiche" bake "$repo/tests/data/blender_small.json" --out "$work/bake" --threads 1 >"$work/bake.log" 2>&1 ||
  { cat "$work/bake.log" >&2; echo "FAIL: seiche bake of tests/data/blender_small.json failed" >&2; exit 1; }
"$seiche" bake "$repo/tests/data/blender_bodies.json" --out "$work/bodies" --threads 1 >"$work/bodies.log" 2>&1 ||
  { cat "$work/bodies.log" >&2; echo "FAIL: seiche bake of tests/data/blender_bodies.json failed" >&2; exit 1; }
blender -b --factory-startup --python-exit-code 1 --python "$repo/tests/blender/addon_test.py" -- \
  "$repo" "$work/bake" "$work/out" "$work/bodies"
