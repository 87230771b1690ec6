#!/usr/bin/env bash
# Fuzzes talus's file loaders with libFuzzer (docs/reliability.md, "Fuzzing"): builds the fuzz
# targets with clang, the address and undefined-behaviour sanitizers in build-fuzz/, runs each
# for SECONDS (default 600) from the saved corpus, then replaces fuzz/corpus/TARGET with a minimal
# set covering the old corpus and the new inputs (libFuzzer's -merge into an empty folder). A
# finding stops that target's run, leaves its input as build-fuzz/findings/TARGET/crash-* and
# makes the script exit 1; fix the loader, keep the input in fuzz/regressions/TARGET, rerun.
#
# usage: fuzz/run.sh [SECONDS] [TARGET...]     (targets: scenario machine pile run)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
seconds=${1:-600}
shift || true
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(scenario machine pile run)
build="$root/build-fuzz"

cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DTALUS_FUZZ=ON -DTALUS_BUILD_TESTS=OFF -DTALUS_BUILD_BENCH=OFF \
  -DTALUS_PYTHON=OFF >/dev/null
cmake --build "$build" -j "$(nproc)" --target "${targets[@]/#/fuzz_}"

status=0
for t in "${targets[@]}"; do
  work="$build/corpus/$t" findings="$build/findings/$t"
  mkdir -p "$work" "$findings"
  # fuzz from the saved corpus into the working one; the log's last lines carry the counts
  started=$(date +%s)
  if ! "$build/fuzz/fuzz_$t" -max_total_time="$seconds" -dict="$root/fuzz/json.dict" -print_final_stats=1 \
      -artifact_prefix="$findings/" -timeout=20 -rss_limit_mb=4096 "$work" "$root/fuzz/corpus/$t" \
      > "$build/fuzz_$t.log" 2>&1; then
    echo "fuzz $t: a finding, see $build/fuzz_$t.log and $findings/" >&2
    status=1
  fi
  elapsed=$(( $(date +%s) - started ))
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$build/fuzz_$t.log" | grep -o '[0-9]*$' || echo "?")
  # the repository's corpus becomes a minimal set covering every edge of what it had and what
  # was found (edges only, -use_counters=0: a third of the files of a hit-count-minimal set)
  merged="$build/merged/$t"
  rm -rf "$merged" && mkdir -p "$merged"
  if "$build/fuzz/fuzz_$t" -merge=1 -use_counters=0 "$merged" "$root/fuzz/corpus/$t" "$work" > "$build/merge_$t.log" 2>&1; then
    rm -rf "$root/fuzz/corpus/$t" && cp -r "$merged" "$root/fuzz/corpus/$t"
  fi
  echo "fuzz $t: $runs executions in $elapsed s, corpus $(ls "$root/fuzz/corpus/$t" | wc -l) files" \
       "($(du -sk "$root/fuzz/corpus/$t" | cut -f1) kB), findings $(ls "$findings" | wc -l)"
done
exit $status
