#!/usr/bin/env bash
# Runs every benchmark built into BUILD/bench/. Each prints its figures beside a naive reference
# measured in the same run, and the ratio between them.
set -euo pipefail
build=${1:-build}
shopt -s nullglob
benches=("$build"/bench/bench_*)
if [ ${#benches[@]} -eq 0 ]; then
  echo "bench: no benchmarks built in $build/bench" >&2
  exit 1
fi
for b in "${benches[@]}"; do
  echo "== $(basename "$b")"
  "$b" --benchmark_counters_tabular=true
done
