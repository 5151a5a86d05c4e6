#!/usr/bin/env bash
# Every host test under ASan + UBSan (make sanitize; docs/TESTING.md "Every test under ASan + UBSan"):
# an optimised clang tree of its own built with -DOMNILOC_SANITIZE=ON (no libFuzzer coverage), every
# host GoogleTest executable run with nothing left out, the long tests in their short mode
# (OMNILOC_TEST_SHORT=1, tests/host/short_mode.hpp).
#
#   scripts/sanitize.sh SRC OUT     configure and build OUT, run the tests; fails on any failed test
#                                   or sanitizer report
#
# SANITIZE_PARALLEL (default 2) executables run at a time, the longest of the last run first
# (OUT/sanitize-times.txt); GTESTS="test_field ..." limits the run to some executables; SANITIZE_JOBS
# (default nproc) is the build's parallelism. Every process's reports (the tests' and the programs
# they start) go to OUT/sanitizer-reports/, one file per process; each executable's output to
# OUT/sanitize-logs/<name>.log.
set -euo pipefail
src=$(realpath "$1")
out=$(realpath -m "$2")
parallel=${SANITIZE_PARALLEL:-2}
jobs=${SANITIZE_JOBS:-$(nproc)}
per_exe_timeout=${SANITIZE_TIMEOUT_S:-1800}

fail() { echo "sanitize: FAILED: $*" >&2; exit 1; }
command -v clang++ >/dev/null 2>&1 || fail "clang++ not found (make deps)"

configure() {
  mkdir -p "$out"
  if [ -f "$out/CMakeCache.txt" ]; then
    cmake -S "$src" -B "$out" >"$out/configure.log" 2>&1 || { cat "$out/configure.log"; fail "reconfigure $out"; }
    return
  fi
  local gen=() launcher=()
  command -v ninja >/dev/null 2>&1 && gen=(-G Ninja)
  command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  # -O2 (asserts kept: no -DNDEBUG), line tables for the reports' stacks; OMNILOC_SANITIZE adds
  # -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer.
  CC=clang CXX=clang++ cmake -S "$src" -B "$out" "${gen[@]}" "${launcher[@]}" \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 -g1" \
    -DOMNILOC_SANITIZE=ON -DOMNILOC_BUILD_SIM=ON -DOMNILOC_BUILD_TESTS=ON -DOMNILOC_BUILD_CALIBRATION=ON \
    -DOMNILOC_ROS2=OFF >"$out/configure.log" 2>&1 || { cat "$out/configure.log"; fail "configure (clang, -DOMNILOC_SANITIZE=ON)"; }
}

build() {
  local t0=$SECONDS
  # sanitize_gtests (tests/CMakeLists.txt): every host test executable and the programs they start.
  cmake --build "$out" --target sanitize_gtests -j "$jobs" >"$out/build.log" 2>&1 || { tail -60 "$out/build.log"; fail "build (log $out/build.log)"; }
  echo "sanitize: built in $((SECONDS - t0)) s ($out)"
}

# Seconds per executable in short mode, for a fresh tree (no OUT/sanitize-times.txt yet) so that the
# longest start first: the run of record's (docs/TESTING.md "Measured").
default_seconds() {
  case "$1" in
    test_venue_generality) echo 610 ;; test_localizer) echo 350 ;; test_sim_programs) echo 320 ;;
    test_calibration) echo 180 ;; test_replay) echo 100 ;; test_replay_realistic) echo 80 ;;
    test_venues) echo 70 ;; test_matcher) echo 60 ;; test_live_view) echo 30 ;; *) echo 1 ;;
  esac
}

# The executables to run, the longest of the last run first.
executables() {
  local bin name secs
  while read -r bin; do
    [ -n "$bin" ] || continue
    name=$(basename "$bin")
    if [ -n "${GTESTS:-}" ] && ! [[ " $GTESTS " == *" $name "* ]]; then continue; fi
    secs=$(awk -v n="$name" '$1 == n { print $2 }' "$out/sanitize-times.txt" 2>/dev/null || true)
    echo "${secs:-$(default_seconds "$name")} $bin"
  done <"$out/sanitize-gtests.txt" | sort -k1,1nr | awk '{ print $NF }'
}

# Runs one executable; writes "name seconds ran failed reports exit" to $out/sanitize-results/name.
run_one() {
  local bin=$1 name log reports t0 rc=0
  name=$(basename "$bin")
  log="$out/sanitize-logs/$name.log"
  reports="$out/sanitizer-reports/$name"
  mkdir -p "$reports"
  t0=$SECONDS
  (cd "$out" && ASAN_OPTIONS="$ASAN_BASE:log_path=$reports/asan" UBSAN_OPTIONS="$UBSAN_BASE:log_path=$reports/ubsan" \
    timeout "$per_exe_timeout" "$bin") >"$log" 2>&1 || rc=$?
  local secs=$((SECONDS - t0)) ran ok skipped nrep
  ran=$(grep -c '^\[ RUN      \]' "$log" || true)
  ok=$(grep -c '^\[       OK \]' "$log" || true)
  skipped=$(grep -c '^\[  SKIPPED \]' "$log" || true)
  nrep=$(find "$reports" -type f | wc -l)
  echo "$name $secs $ran $((ran - ok - skipped)) $nrep $rc" >"$out/sanitize-results/$name"
  printf 'sanitize: %-28s %5d s  %3d tests ran, %d failed, %d sanitizer reports%s\n' "$name" "$secs" "$ran" \
    "$((ran - ok - skipped))" "$nrep" "$([ "$rc" -eq 0 ] || echo ", exit $rc")"
}

summarise() {
  local total_s=$1 exes=0 ran=0 failed=0 reports=0 bad=() name secs r f n rc times
  # This run's times, and the last run's of the executables GTESTS left out.
  times=$(cat "$out"/sanitize-results/* 2>/dev/null | awk '{ print $1, $2 }')
  { echo "$times"; awk 'NR == FNR { seen[$1] = 1; next } !($1 in seen)' <(echo "$times") \
      "$out/sanitize-times.txt" 2>/dev/null || true; } | sed '/^$/d' >"$out/sanitize-times.new"
  mv "$out/sanitize-times.new" "$out/sanitize-times.txt"
  for res in "$out"/sanitize-results/*; do
    [ -f "$res" ] || continue
    read -r name secs r f n rc <"$res"
    exes=$((exes + 1)) ran=$((ran + r)) failed=$((failed + f)) reports=$((reports + n))
    if [ "$rc" -ne 0 ] || [ "$f" -ne 0 ] || [ "$n" -ne 0 ]; then bad+=("$name"); fi
  done
  for name in "${bad[@]}"; do
    echo "=== $name (log $out/sanitize-logs/$name.log)"
    grep -E '^\[  FAILED  \]' "$out/sanitize-logs/$name.log" | sort -u || true
    for f in "$out/sanitizer-reports/$name"/*; do [ -f "$f" ] && { echo "--- $f"; head -40 "$f"; }; done
    tail -20 "$out/sanitize-logs/$name.log"
  done
  echo "sanitize: $exes executables in $total_s s: $ran tests ran, $failed failed, $reports sanitizer reports (OMNILOC_TEST_SHORT=1)"
  [ "$exes" -gt 0 ] || fail "no test executable run (GTESTS='${GTESTS:-}')"
  [ "${#bad[@]}" -eq 0 ] || fail "under ASan + UBSan: ${bad[*]}"
  echo "sanitize: OK: every host test passed under ASan + UBSan, no report"
}

configure
build
export OMNILOC_TEST_SHORT=1
# As scripts/fuzz.sh gtests: any report aborts the process; OpenCV's gphoto2 backend (whose library
# leaks what it enumerates, not our code) is switched off.
export ASAN_BASE=detect_leaks=1:abort_on_error=1:halt_on_error=1:symbolize=1:detect_stack_use_after_return=0
export UBSAN_BASE=print_stacktrace=1:halt_on_error=1
export OPENCV_VIDEOIO_PRIORITY_GPHOTO2=0
rm -rf "$out/sanitize-results" "$out/sanitize-logs" "$out/sanitizer-reports"
mkdir -p "$out/sanitize-results" "$out/sanitize-logs" "$out/sanitizer-reports"
mapfile -t bins < <(executables)
echo "sanitize: ${#bins[@]} test executables, $parallel at a time, OMNILOC_TEST_SHORT=1"
t0=$SECONDS
running=0
for bin in "${bins[@]}"; do
  if [ "$running" -ge "$parallel" ]; then
    wait -n || true
    running=$((running - 1))
  fi
  run_one "$bin" &
  running=$((running + 1))
done
wait || true
summarise $((SECONDS - t0))
