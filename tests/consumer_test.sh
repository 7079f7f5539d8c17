#!/usr/bin/env bash
# The installed library, as another project uses it (ctest install.consumer, in `make test`):
# installs BUILD_DIR into BUILD_DIR/consumer_test/prefix, builds examples/consumer against it
# with find_package(Seiche) and the same compiler, runs it and checks its numbers (the PBD
# lecture's worked example, then the pair's centre of mass and rest length after 10 frames), and
# imports the installed Python package from its documented folder.
#   tests/consumer_test.sh BUILD_DIR SOURCE_DIR CXX_COMPILER [PYTHON_INSTALL_DIR]
set -euo pipefail
build=$(cd "$1" && pwd) src=$2 cxx=$3 python_dir=${4:-}
work=$build/consumer_test
rm -rf "$work"
mkdir -p "$work"
fail() { echo "consumer_test: $*" >&2; exit 1; }

cmake --install "$build" --prefix "$work/prefix" >"$work/install.log" || fail "cmake --install failed: $(cat "$work/install.log")"
for f in lib/cmake/Seiche/SeicheConfig.cmake lib/cmake/Seiche/SeicheConfigVersion.cmake \
         lib/cmake/Seiche/SeicheTargets.cmake include/seiche/seiche.hpp \
         include/seiche/kernels/particle_view.hpp include/seiche/export/scene_exporters.hpp bin/seiche; do
  [ -e "$work/prefix/$f" ] || fail "not installed: $f"
done
for layer in core kernels neighbor export; do  # shared with OpenVDB, static without
  compgen -G "$work/prefix/lib/libseiche_$layer.[as]*" >/dev/null || fail "not installed: lib/libseiche_$layer"
done
# What is installed needs nothing of the build tree: every Seiche library a program loads comes
# from the prefix (RPATH relative to each file, cmake/SeicheInstall.cmake).
only_prefix_libs() {
  local where
  where=$(ldd "$1" | awk '/libseiche_/ { print $3 }')
  if [ -n "$(grep -v "^$work/prefix/" <<<"$where")" ]; then fail "$1 loads Seiche from outside the prefix: $where"; fi
}
only_prefix_libs "$work/prefix/bin/seiche"

cmake -S "$src/examples/consumer" -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_PREFIX_PATH="$work/prefix" >"$work/configure.log" 2>&1 ||
  fail "find_package(Seiche) / configure failed: $(cat "$work/configure.log")"
cmake --build "$work/build" >"$work/build.log" 2>&1 || fail "the consumer does not build: $(cat "$work/build.log")"
only_prefix_libs "$work/build/seiche_consumer"
"$work/build/seiche_consumer" "$work/out" >"$work/output.txt" || fail "the consumer failed: $(cat "$work/output.txt")"
cat "$work/output.txt"

expect() { grep -qxF "$1" "$work/output.txt" || fail "expected the line: $1"; }
expect "frame 1 particle 0: 4.666667 3.166667 2.333333"  # (14/3, 19/6, 7/3)
expect "frame 1 particle 1: 2.666667 4.166667 4.333333"  # (8/3, 25/6, 13/3)
# After 10 frames: still at rest length 3, the centre of mass still at (13/3, 10/3, 8/3).
awk '/^frame 10: distance/ { d = $4 + 0; cx = $8 + 0; cy = $9 + 0; cz = $10 + 0; found = 1 }
     function off(a, b) { return a > b ? a - b : b - a }
     END { exit !(found && off(d, 3) < 1e-4 && off(cx, 13/3) < 1e-4 && off(cy, 10/3) < 1e-4 && off(cz, 8/3) < 1e-4) }' \
  "$work/output.txt" || fail "frame 10: rest length or centre of mass off"
[ -s "$work/out/particles.0010.ply" ] || fail "no particles.0010.ply"
# The installed command line runs (no RPATH into the build tree is needed: nothing of ours is shared).
"$work/prefix/bin/seiche" --version | grep -q '^seiche [0-9]' || fail "the installed bin/seiche does not run"

if [ -n "$python_dir" ]; then
  only_prefix_libs "$(echo "$work/prefix/$python_dir"/seiche/_seiche*.so)"
  PYTHONPATH="$work/prefix/$python_dir" /usr/bin/python3 -c "
import seiche, sys
assert seiche.__file__.startswith('$work/prefix/'), seiche.__file__
sim = seiche.Simulation('$src/scenes/seed_example.json')
sim.step()
print('installed python package:', seiche.__file__, 'particles', len(sim))
" || fail "the installed Python package does not import from $python_dir"
fi
echo "consumer_test: ok"
