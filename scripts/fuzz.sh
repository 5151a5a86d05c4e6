#!/usr/bin/env bash
# The sanitizer tree (docs/TESTING.md): a clang tree built with -DOMNILOC_FUZZ=ON (ASan + UBSan +
# libFuzzer coverage on everything), holding the libFuzzer harnesses of tests/fuzz and the host
# GoogleTest executables, so that the library is compiled once for both.
#
#   scripts/fuzz.sh build   SRC OUT            configure and build the harnesses into OUT
#   scripts/fuzz.sh run     SRC OUT SECONDS    build, then fuzz each harness for SECONDS (make fuzz):
#                                              new inputs go to OUT/fuzz-corpus/<name>/ (the seed
#                                              corpus is only read), crashes to OUT/fuzz-findings/
#   scripts/fuzz.sh regress SRC OUT            build, then run each harness once over every input of
#                                              tests/fuzz/corpus/<name>/ and tests/fuzz/regressions/<name>/
#                                              (CTest fuzz_regressions); fails on any report
#   scripts/fuzz.sh gtests  SRC OUT            build the host GoogleTest executables in OUT and run each
#                                              (CTest sanitize_gtests), the long simulation tests
#                                              left out (SANITIZE_GTEST_EXCLUDE below); fails on any
#                                              report or failed test
# HARNESSES="frame_decoder control" limits run/regress to some harnesses; GTESTS="test_field ..." limits
# gtests to some executables.
set -euo pipefail
mode=$1
src=$(realpath "$2")
out=$(realpath -m "$3")
seconds=${4:-60}

gen=()
command -v ninja >/dev/null 2>&1 && gen=(-G Ninja)
launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
jobs=${FUZZ_JOBS:-$(nproc)}

fail() { echo "fuzz: FAILED: $*" >&2; exit 1; }

build() {
  mkdir -p "$out"
  # Configured when new or when made before the tree held the tests; an existing tree is
  # reconfigured first (cheap), because a build that leaves the regeneration to ninja first builds
  # the Verilator outputs CMake includes with the old flags (after an include path moved, that
  # build fails before CMake runs again).
  if grep -q '^OMNILOC_BUILD_TESTS:BOOL=ON' "$out/CMakeCache.txt" 2>/dev/null; then
    cmake -S "$src" -B "$out" >"$out/configure.log" 2>&1 || { cat "$out/configure.log"; fail "reconfigure $out"; }
  else
    CC=clang CXX=clang++ cmake -S "$src" -B "$out" "${gen[@]}" "${launcher[@]}" \
      -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -gline-tables-only" -DCMAKE_C_FLAGS_DEBUG="-O1 -gline-tables-only" \
      -DOMNILOC_FUZZ=ON -DOMNILOC_BUILD_SIM=ON -DOMNILOC_BUILD_TESTS=ON -DOMNILOC_BUILD_CALIBRATION=ON \
      -DOMNILOC_ROS2=OFF >"$out/configure.log" 2>&1 || { cat "$out/configure.log"; fail "configure (clang, -DOMNILOC_FUZZ=ON)"; }
  fi
  local target=$1 t0=$SECONDS
  cmake --build "$out" --target "$target" -j "$jobs" >"$out/build-$target.log" 2>&1 || { tail -60 "$out/build-$target.log"; fail "build $target"; }
  echo "fuzz: $target built in $out ($((SECONDS - t0)) s)"
}

harnesses() {
  if [ -n "${HARNESSES:-}" ]; then
    for h in $HARNESSES; do echo "$h"; done
  else
    for f in "$src"/tests/fuzz/fuzz_*.cpp; do basename "$f" .cpp | sed 's/^fuzz_//'; done
  fi
}

# Every input of a harness's seed corpus and regressions (files; README files excluded).
inputs_of() {
  local h=$1 d
  for d in "$src/tests/fuzz/corpus/$h" "$src/tests/fuzz/regressions/$h"; do
    [ -d "$d" ] && find "$d" -type f ! -name 'README*' | sort
  done
  return 0
}

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:symbolize=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

if [ "$mode" = gtests ]; then build sanitize_gtests; else build fuzzers; fi
case "$mode" in
  build) ;;
  run)
    summary=()
    failed=0
    for h in $(harnesses); do
      bin="$out/fuzz/fuzz_$h"
      [ -x "$bin" ] || fail "no harness $bin"
      work="$out/fuzz-corpus/$h"
      findings="$out/fuzz-findings/$h"
      mkdir -p "$work" "$findings"
      seeds=()
      [ -d "$src/tests/fuzz/corpus/$h" ] && seeds+=("$src/tests/fuzz/corpus/$h")
      [ -d "$src/tests/fuzz/regressions/$h" ] && seeds+=("$src/tests/fuzz/regressions/$h")
      log="$out/fuzz-findings/$h.log"
      echo "=== fuzz_$h: ${seconds} s"
      rc=0
      "$bin" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 -print_final_stats=1 \
        -artifact_prefix="$findings/" "$work" "${seeds[@]}" >"$log" 2>&1 || rc=$?
      grep -E '^#[0-9]+[[:space:]]+(INITED|DONE)|stat::number_of_executed_units|stat::peak_rss_mb|stat::new_units_added' "$log" || true
      execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
      cov=$(grep -oE 'cov: [0-9]+' "$log" | tail -1 | cut -d' ' -f2)
      if [ "$rc" -ne 0 ]; then
        failed=1
        tail -40 "$log"
        summary+=("fuzz_$h: FINDING (exit $rc) after ${execs:-?} executions, see $log and $findings/")
      else
        summary+=("fuzz_$h: ${execs:-?} executions in ${seconds} s, coverage ${cov:-?} edges, corpus $(find "$work" -type f | wc -l) inputs, no finding")
      fi
    done
    echo "=== summary"
    printf '%s\n' "${summary[@]}"
    [ "$failed" -eq 0 ] || fail "a harness found a bug: keep the input under tests/fuzz/regressions/<harness>/ (docs/TESTING.md)"
    ;;
  regress)
    total=0
    for h in $(harnesses); do
      bin="$out/fuzz/fuzz_$h"
      [ -x "$bin" ] || fail "no harness $bin"
      mapfile -t files < <(inputs_of "$h")
      [ "${#files[@]}" -gt 0 ] || fail "fuzz_$h has no seed corpus (tests/fuzz/corpus/$h/)"
      log="$out/fuzz-regress-$h.log"
      if ! "$bin" -timeout=30 -rss_limit_mb=2048 -malloc_limit_mb=1024 "${files[@]}" >"$log" 2>&1; then
        tail -60 "$log"
        fail "fuzz_$h on its corpus and regressions (log $log)"
      fi
      ran=$(grep -c '^Executed ' "$log" || true)
      [ "$ran" -eq "${#files[@]}" ] || { tail -20 "$log"; fail "fuzz_$h ran $ran of ${#files[@]} inputs"; }
      echo "fuzz: fuzz_$h: ${#files[@]} inputs, no report"
      total=$((total + ${#files[@]}))
    done
    echo "fuzz: OK: $total inputs over $(harnesses | wc -l) harnesses, no sanitizer report, no crash"
    ;;
  gtests)
    # Left out under the sanitizers (docs/TESTING.md "The test suite under ASan + UBSan"): the long
    # simulation tests, each over 5 s in the Release build and several times that at -O1 with ASan;
    # the same code paths run in the shorter tests of the same executables.
    exclude=${SANITIZE_GTEST_EXCLUDE-$(sed -e 's/#.*//' -e 's/[[:space:]]//g' -e '/^$/d' "$src/tests/sanitize_gtest_exclude.txt" | paste -sd:)}
    export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:halt_on_error=1:symbolize=1:detect_stack_use_after_return=0
    export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
    # cv::VideoCapture::open with CAP_ANY probes OpenCV's gphoto2 backend, whose libgphoto2 leaks the
    # USB device lists it enumerates (45 kB per open; not our code, and its stack is lost in the
    # uninstrumented library, so LeakSanitizer cannot suppress it by name): the backend is switched off.
    export OPENCV_VIDEOIO_PRIORITY_GPHOTO2=0
    mapfile -t bins < "$out/sanitize-gtests.txt"
    failed=()
    total_t0=$SECONDS
    ran=0
    for bin in "${bins[@]}"; do
      [ -n "$bin" ] || continue
      name=$(basename "$bin")
      if [ -n "${GTESTS:-}" ] && ! [[ " $GTESTS " == *" $name "* ]]; then continue; fi
      log="$out/gtests-$name.log"
      t0=$SECONDS
      rc=0
      (cd "$out" && "$bin" --gtest_filter="-$exclude") >"$log" 2>&1 || rc=$?
      n=$(sed -n 's/^\[==========\] \([0-9]*\) tests\? from .* ran\..*/\1/p' "$log" | tail -1)
      if [ "$rc" -ne 0 ]; then
        failed+=("$name")
        tail -60 "$log"
        echo "fuzz: gtests: $name FAILED (exit $rc, $((SECONDS - t0)) s; log $log)"
      else
        echo "fuzz: gtests: $name: ${n:-?} tests passed, no report ($((SECONDS - t0)) s)"
      fi
      ran=$((ran + 1))
    done
    [ "$ran" -gt 0 ] || fail "no test executable run (GTESTS='${GTESTS:-}')"
    [ "${#failed[@]}" -eq 0 ] || fail "under ASan + UBSan: ${failed[*]}"
    echo "fuzz: OK: $ran test executables under ASan + UBSan in $((SECONDS - total_t0)) s, no report, every test passed"
    ;;
  *) fail "unknown mode '$mode' (build, run, regress or gtests)" ;;
esac
