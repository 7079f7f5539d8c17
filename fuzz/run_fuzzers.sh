#!/usr/bin/env bash
# Runs each libFuzzer target of a fuzz build (make fuzz builds them in build/fuzz) for
# FUZZ_SECONDS seconds (default 60), one after the other, and says how many inputs each ran.
#   fuzz_scene_loader       seeds: scenes/*.json, and each mesh of tests/data/ as a cloth and as a
#                           collider (a scene, "--- fuzz.obj ---", the OBJ: fuzz_scene_loader.cpp);
#                           dictionary: the quoted words of the scene readers
#   fuzz_checkpoint_reader  seeds: real checkpoints written by write_checkpoint_seeds
# The corpus each run grows is kept in <build>/corpus/<target> for the next run. A finding (a
# crash, an unexpected exception, a leak, a sanitizer report, an input slower than 10 s or over
# 2 GB) stops its target, leaves the input in <build>/findings/ and makes this script exit 1.
# Usage: fuzz/run_fuzzers.sh [build folder]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/fuzz}
seconds=${FUZZ_SECONDS:-60}

mkdir -p "$build/seeds/scene_loader" "$build/seeds/checkpoint_reader" "$build/findings" \
         "$build/corpus/fuzz_scene_loader" "$build/corpus/fuzz_checkpoint_reader" "$build/logs"
cp scenes/*.json "$build/seeds/scene_loader/"
for obj in tests/data/*.obj; do
  for use in cloths colliders; do
    { printf '{ "domain": { "min": [-2, -2, -2], "max": [2, 2, 2] },\n'
      printf '  "%s": [ { "mesh": { "file": "fuzz.obj" } } ] }\n--- fuzz.obj ---\n' "$use"
      cat "$obj"; } > "$build/seeds/scene_loader/$use-$(basename "$obj" .obj).txt"
  done
done
"$build/fuzz/write_checkpoint_seeds" "$build/seeds/checkpoint_reader"
# The scene dictionary: every quoted lowercase word of the scene readers (keys, section names,
# enumerated values), so that it follows the key tables as they change.
{
  grep -ohE '"[a-z_0-9]+"' core/src/scene/*.cpp core/src/families/*/*_reader.cpp | sort -u
  printf '%s\n' '"{"' '"}"' '"["' '"]"' '":"' '","' '"true"' '"false"' '"null"' '"1e39"' '"-0"'
} > "$build/seeds/scene.dict"

export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
status=0
run() {
  local target=$1 seeds=$2; shift 2
  local log="$build/logs/$target.log"
  echo "fuzz: $target for $seconds s"
  if "$build/fuzz/$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
       -print_final_stats=1 -artifact_prefix="$build/findings/$target-" "$@" \
       "$build/corpus/$target" "$seeds" >"$log" 2>&1; then
    echo "fuzz: $target: no finding; $(grep -m1 -oE 'Done [0-9]+ runs in [0-9]+ second' "$log" | sed 's/Done \([0-9]*\) runs in \([0-9]*\) second/\1 inputs in \2 s/'), $(grep -m1 INITED "$log" | grep -oE 'cov: [0-9]+' | grep -oE '[0-9]+') code edges covered by the corpus at start, $(grep -E 'DONE' "$log" | grep -oE 'cov: [0-9]+' | grep -oE '[0-9]+') at the end, $(ls "$build/corpus/$target" | wc -l) inputs in the corpus ($log)"
  else
    echo "fuzz: $target FOUND A PROBLEM: $(ls -t "$build/findings/" | grep "^$target-" | head -1) in $build/findings/; the report:" >&2
    grep -m1 -A30 -E 'ERROR|runtime error|==[0-9]+==|terminate called|uncaught' "$log" >&2 || tail -40 "$log" >&2
    status=1
  fi
}
run fuzz_scene_loader "$build/seeds/scene_loader" -dict="$build/seeds/scene.dict" -max_len=4096
run fuzz_checkpoint_reader "$build/seeds/checkpoint_reader" -max_len=16384
exit $status
