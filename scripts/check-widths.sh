#!/usr/bin/env bash
# Compiles the SIMD code for the widths this machine may not be able to run, so that a change that
# breaks one fails here (and in CI) on any machine: the kernels and the neighbor search (CMake
# targets seiche_kernels and seiche_neighbor, with the header-only SIMD layer under them), Release,
# warnings as errors, each width in its own build/widths/<width>. Compile only: nothing is linked
# into a program, nothing runs.
#
#   scripts/check-widths.sh                    x86-64 (SSE2), x86-64-v3 (AVX2), x86-64-v4 (AVX-512)
#                                              and aarch64 (NEON)
#   scripts/check-widths.sh x86-64-v4 znver4   only these
#
# A name is a -march value for this machine's g++, except aarch64: -march=armv8-a with Debian's
# cross compiler (g++-aarch64-linux-gnu, which scripts/install-ci-deps.sh installs) through
# cmake/aarch64-linux-gnu.cmake. `make check-widths` installs what is missing and runs this.
# JOBS sets the parallel compiles (default: every core).
set -euo pipefail
cd "$(dirname "$0")/.."

widths=("$@")
[ ${#widths[@]} -gt 0 ] || widths=(x86-64 x86-64-v3 x86-64-v4 aarch64)
jobs=${JOBS:-$(nproc)}
targets=(seiche_kernels seiche_neighbor)
# Configure only what the two targets need: no tests, benchmarks, OpenVDB or Python module.
common=(-G Ninja -DCMAKE_BUILD_TYPE=Release -DSEICHE_WERROR=ON -DSEICHE_BUILD_TESTS=OFF
        -DSEICHE_BUILD_BENCHMARKS=OFF -DSEICHE_WITH_OPENVDB=OFF -DSEICHE_BUILD_PYTHON=OFF)

# Shows why a width failed: the configure log, or ninja's report from its first failed compile
# (a template error in xsimd can run to thousands of lines; the whole log stays on disk).
show_failure() {
  local log=$1 from
  from=$(grep -n -m1 '^FAILED:' "$log" | cut -d: -f1 || true)
  sed -n "${from:-1},\$p" "$log" | head -n 150
  [ "$(sed -n "${from:-1},\$p" "$log" | wc -l)" -le 150 ] || echo "... (cut; the whole log: $log)"
}

mkdir -p build/widths
failed=()
all_start=$SECONDS
for w in "${widths[@]}"; do
  dir=build/widths/$w
  log=build/widths/$w.log
  if [ "$w" = aarch64 ]; then
    march=armv8-a
    flags=(-DCMAKE_TOOLCHAIN_FILE="$PWD/cmake/aarch64-linux-gnu.cmake" -DSEICHE_MARCH=$march)
    if ! command -v aarch64-linux-gnu-g++ >/dev/null; then
      echo "check-widths: aarch64: no cross compiler (aarch64-linux-gnu-g++); run scripts/install-ci-deps.sh" >&2
      failed+=("$w")
      continue
    fi
  else
    march=$w
    flags=(-DSEICHE_MARCH="$march")
  fi
  start=$SECONDS
  if ! cmake -S . -B "$dir" "${common[@]}" "${flags[@]}" >"$log" 2>&1; then
    echo "check-widths: $w: CMake configure failed:" >&2
    show_failure "$log" >&2
    failed+=("$w")
    continue
  fi
  if ! cmake --build "$dir" --target "${targets[@]}" -j "$jobs" >>"$log" 2>&1; then
    echo "check-widths: $w (-march=$march): does NOT compile:" >&2
    show_failure "$log" >&2
    failed+=("$w")
    continue
  fi
  # A check that silently built for another width would check nothing: every compile of the two
  # targets must carry this width's -march (the last -march on a g++ command line wins, and
  # SEICHE_MARCH's comes after CMAKE_CXX_FLAGS).
  wrong=$(ninja -C "$dir" -t commands "${targets[@]}" | { grep -e ' -c ' || echo "(no compiles)"; } |
          awk -v want="-march=$march" '{ m = "(no -march)"
                                         for (i = 1; i <= NF; i++) if ($i ~ /^-march=/) m = $i
                                         if (m != want) print m }' | sort -u)
  if [ -n "$wrong" ]; then
    echo "check-widths: $w: some compiles use ${wrong//$'\n'/ }, not -march=$march (see $dir/build.ninja)" >&2
    failed+=("$w")
    continue
  fi
  echo "check-widths: $w (-march=$march) compiles: $((SECONDS - start)) s"
done

if [ ${#failed[@]} -gt 0 ]; then
  echo "check-widths: FAILED for ${failed[*]} (of ${widths[*]}); logs in build/widths/" >&2
  exit 1
fi
echo "check-widths: all ${#widths[@]} widths compile (${widths[*]}): $((SECONDS - all_start)) s"
