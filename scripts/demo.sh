#!/usr/bin/env bash
# `make demo`: the robot's daemon on the simulated robot, no hardware (docs/DAEMON.md, "make demo").
# Runs BUILD/bin/omniloc-sim demo with its output (paths.png, errors.csv) in BUILD/demo/; exits
# with the demo's status (1 when the daemon never fixed or did not recover from the kidnapping).
# Usage: scripts/demo.sh [BUILD_DIR] [extra `omniloc-sim demo` options, e.g. --camera-hz 30]
set -euo pipefail
build=$(realpath -m "${1:-build}")
shift || true
bin="$build/bin/omniloc-sim"
if [ ! -x "$bin" ]; then
  echo "demo: $bin is not built; run 'make build' (or cmake --build $build --target omniloc_sim_cli)" >&2
  exit 1
fi
mkdir -p "$build/demo"
start=$(date +%s)
status=0
"$bin" demo --out "$build/demo" "$@" || status=$?
echo "demo: finished in $(( $(date +%s) - start )) s wall (exit status $status); plot: $build/demo/paths.png"
exit $status
