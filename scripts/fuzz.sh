#!/usr/bin/env bash
# The libFuzzer harnesses of tests/fuzz (docs/TESTING.md "Fuzzing") in a clang tree built with
# -DOMNILOC_FUZZ=ON (ASan + UBSan + libFuzzer; the simulator, the tests and the calibration off).
#
#   scripts/fuzz.sh build   SRC OUT            configure and build the harnesses into OUT
#   scripts/fuzz.sh run     SRC OUT SECONDS    build, then fuzz each harness for SECONDS (make fuzz):
#                                              new inputs go to OUT/fuzz-corpus/<name>/ (the seed
#                                              corpus is only read), crashes to OUT/fuzz-findings/
#   scripts/fuzz.sh regress SRC OUT            build, then run each harness once over every input of
#                                              tests/fuzz/corpus/<name>/ and tests/fuzz/regressions/<name>/
#                                              (CTest fuzz_regressions); fails on any report
# HARNESSES="frame_decoder control" limits either to some harnesses.
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
  if [ ! -f "$out/CMakeCache.txt" ]; then
    CC=clang CXX=clang++ cmake -S "$src" -B "$out" "${gen[@]}" "${launcher[@]}" \
      -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" -DCMAKE_C_FLAGS_DEBUG="-O1 -g" \
      -DOMNILOC_FUZZ=ON -DOMNILOC_BUILD_SIM=OFF -DOMNILOC_BUILD_TESTS=OFF -DOMNILOC_BUILD_CALIBRATION=OFF \
      -DOMNILOC_ROS2=OFF >"$out/configure.log" 2>&1 || { cat "$out/configure.log"; fail "configure (clang, -DOMNILOC_FUZZ=ON)"; }
  fi
  local t0=$SECONDS
  cmake --build "$out" --target fuzzers -j "$jobs" >"$out/build.log" 2>&1 || { tail -60 "$out/build.log"; fail "build"; }
  echo "fuzz: harnesses built in $out/fuzz ($((SECONDS - t0)) s)"
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

build
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
  *) fail "unknown mode '$mode' (build, run or regress)" ;;
esac
