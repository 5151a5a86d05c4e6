#!/usr/bin/env bash
# `make demo`: the whole system on the simulated robot, no hardware (docs/DAEMON.md, "make demo").
# Runs BUILD/bin/omniloc demo with its output (paths.png, errors.csv) in BUILD/demo/.
# Usage: scripts/demo.sh [BUILD_DIR] [extra `omniloc demo` options, e.g. --camera-hz 30]
set -euo pipefail
build=$(realpath -m "${1:-build}")
shift || true
bin="$build/bin/omniloc"
if [ ! -x "$bin" ]; then
  echo "demo: $bin is not built; run 'make build' (or cmake --build $build --target omniloc_cli)" >&2
  exit 1
fi
mkdir -p "$build/demo"
start=$(date +%s)
"$bin" demo --out "$build/demo" "$@"
echo "demo: finished in $(( $(date +%s) - start )) s wall; plot: $build/demo/paths.png"
