#!/usr/bin/env bash
# Formal checks of one gyro module (rtl/gyro/) with yosys + yosys-smtbmc (z3), no SymbiYosys:
#   bmc:       every assert holds for DEPTH steps from reset
#   induction: k-induction with DEPTH (with bmc: a full proof)
#   cover:     every `cover` statement is reached within COVER_DEPTH steps (a trace per cover),
#              so no property is vacuous (COVER_DEPTH 0: no cover run)
# On failure it prints the tail of the log and the counterexample / trace path and exits 1.
#
# usage: gyro_formal.sh TOP DEPTH COVER_DEPTH OUTDIR "CHPARAMS" FILE...
#   CHPARAMS is a yosys chparam argument list or "". SMTBMC_FLAGS (environment) adds
#   yosys-smtbmc options (e.g. --unroll).
set -euo pipefail

if [[ $# -lt 6 ]]; then
  echo "usage: $0 TOP DEPTH COVER_DEPTH OUTDIR CHPARAMS FILE..." >&2
  exit 2
fi
top=$1 depth=$2 cover_depth=$3 outdir=$4 chparams=$5
shift 5
files=("$@")
mkdir -p "$outdir"
smt2="$outdir/$top.smt2"
log="$outdir/$top.log"

chparam_cmd=""
if [[ -n $chparams ]]; then chparam_cmd="chparam $chparams $top;"; fi
if ! yosys -q -l "$log.yosys" -p "read_verilog -formal ${files[*]}; $chparam_cmd prep -top $top; async2sync; dffunmap; write_smt2 -wires $smt2"; then
  echo "FORMAL $top: yosys failed, log: $log.yosys" >&2
  exit 1
fi

run() {  # $1 = label, $2 = depth, rest = extra yosys-smtbmc args
  local label=$1 d=$2; shift 2
  local vcd="$outdir/${top}_${label}.vcd"
  local start=$SECONDS
  rm -f "$outdir/${top}_${label}"*.vcd
  if yosys-smtbmc -s z3 ${SMTBMC_FLAGS:-} "$@" -t "$d" --dump-vcd "$vcd" "$smt2" > "$log.$label" 2>&1 \
      && grep -q "Status: PASSED" "$log.$label"; then
    echo "FORMAL $top: $label depth $d PASSED ($((SECONDS - start)) s)"
  else
    tail -n 20 "$log.$label"
    echo "FORMAL $top: $label depth $d FAILED"
    ls "$outdir/${top}_${label}"*.vcd 2>/dev/null | sed 's/^/trace: /' || true
    echo "full log: $log.$label"
    exit 1
  fi
}

run bmc "$depth"
run induction "$depth" -i
if [[ $cover_depth -gt 0 ]]; then
  run cover "$cover_depth" -c
  # yosys-smtbmc -c passes only if every cover was reached.
  echo "FORMAL $top: covers reached: $(grep -c 'Reached cover statement' "$log.cover")"
fi
