#!/usr/bin/env bash
# Prove the `ifdef FORMAL properties of one RTL module with yosys + yosys-smtbmc (z3).
# No SymbiYosys on this machine, so this script does what an .sby file would:
#   yosys: read_verilog -formal, chparam, prep, async2sync, dffunmap, write_smt2
#   prove: BMC base case to DEPTH, then k-induction with DEPTH
#   bmc:   bounded model check to DEPTH only (used where induction does not close)
#   cover: with COVER_DEPTH (environment) > 0, afterwards every `cover` statement must be reached
#          within COVER_DEPTH steps (a trace each), so that no property holds vacuously; no cover
#          at all fails too (the properties were compiled out)
# On failure it prints the counterexample VCD path and exits 1.
#
# usage: run_formal.sh NAME TOP MODE DEPTH OUTDIR INCLUDE_DIR "CHPARAMS" FILE...
#   CHPARAMS is a yosys chparam argument list (e.g. "-set CLK_HZ 8 -set TICK_HZ 1") or "".
#   SMTBMC_FLAGS (environment, optional) adds yosys-smtbmc options, e.g. --unroll where z3's
#   incremental mode stalls (frame_rx).
set -euo pipefail

if [[ $# -lt 8 ]]; then
  echo "usage: $0 NAME TOP MODE(prove|bmc) DEPTH OUTDIR INCLUDE_DIR CHPARAMS FILE..." >&2
  exit 2
fi
name=$1 top=$2 mode=$3 depth=$4 outdir=$5 incdir=$6 chparams=$7
shift 7
files=("$@")

case $mode in prove|bmc) ;; *) echo "$0: mode must be prove or bmc, got '$mode'" >&2; exit 2 ;; esac
mkdir -p "$outdir"
smt2="$outdir/$name.smt2"
log="$outdir/$name.log"

chparam_cmd=""
if [[ -n $chparams ]]; then chparam_cmd="chparam $chparams $top;"; fi

# FORMAL_TOP_<TOP> (upper case) lets a module keep properties that only its own proof checks
# (crc16_ccitt: an equivalence that would weigh down every proof instantiating it).
top_define="FORMAL_TOP_${top^^}"
if ! yosys -q -l "$log.yosys" -p "read_verilog -formal -D$top_define -I$incdir ${files[*]}; $chparam_cmd prep -top $top; async2sync; dffunmap; write_smt2 -wires $smt2"; then
  echo "FORMAL $name: yosys failed, log: $log.yosys" >&2
  exit 1
fi

run_smtbmc() {  # $1 = label, $2 = depth, rest = extra yosys-smtbmc args
  local label=$1 d=$2; shift 2
  local vcd="$outdir/${name}_${label}_cex.vcd"
  local start=$SECONDS
  rm -f "$outdir/${name}_${label}"*.vcd
  if yosys-smtbmc -s z3 ${SMTBMC_FLAGS:-} "$@" -t "$d" --dump-vcd "$vcd" "$smt2" > "$log.$label" 2>&1 \
      && grep -q "Status: PASSED" "$log.$label"; then
    echo "FORMAL $name: $label depth $d PASSED ($((SECONDS - start)) s)"
  else
    tail -n 20 "$log.$label"
    echo "FORMAL $name: $label depth $d FAILED"
    ls "$outdir/${name}_${label}"*.vcd 2>/dev/null | sed 's/^/trace: /' || true
    echo "full log: $log.$label"
    exit 1
  fi
}

run_smtbmc bmc "$depth"
if [[ $mode == prove ]]; then
  run_smtbmc induction "$depth" -i
fi
cover_depth=${COVER_DEPTH:-0}
if [[ $cover_depth -gt 0 ]]; then
  run_smtbmc cover "$cover_depth" -c  # passes only if every cover was reached
  reached=$(grep -c 'Reached cover statement' "$log.cover" || true)
  # No cover at all passes yosys-smtbmc -c vacuously: the properties were compiled out (a wrong
  # `ifdef, e.g. FORMAL_TOP_<TOP> misspelt), so every assertion above held vacuously too.
  if [[ $reached -eq 0 ]]; then
    echo "FORMAL $name: no cover statement reached: are the module's properties compiled in ($top_define)?" >&2
    exit 1
  fi
  echo "FORMAL $name: covers reached: $reached"
fi
