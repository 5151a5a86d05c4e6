#!/usr/bin/env bash
# Logic cells of the gyro reader (gyro_ctrl with its spi_master and gyro_accum) on the iCE40:
# yosys synth_ice40, then nextpnr-ice40 packing and placement. The HX8K/CT256 stands in for the
# board's UP5K only because the standalone module has more ports than the SG48 has pins; the logic
# cell (LUT4 + carry + flip-flop) is the same on both families. Fails if the count exceeds MAX_LC.
#
# usage: gyro_synth_lc.sh OUTDIR MAX_LC [-IDIR] FILE...   (read_verilog's arguments)
set -euo pipefail
if [[ $# -lt 3 ]]; then
  echo "usage: $0 OUTDIR MAX_LC FILE..." >&2
  exit 2
fi
outdir=$1 max_lc=$2
shift 2
mkdir -p "$outdir"
yosys -q -l "$outdir/yosys.log" -p "read_verilog $*; synth_ice40 -top gyro_ctrl -json $outdir/gyro_ctrl.json"
nextpnr-ice40 --hx8k --package ct256 --json "$outdir/gyro_ctrl.json" --pcf-allow-unconstrained \
  --freq 12 --seed 1 -q -l "$outdir/nextpnr.log" 2>/dev/null
lc=$(sed -n 's/.*ICESTORM_LC: *\([0-9]*\)\/.*/\1/p' "$outdir/nextpnr.log" | head -n 1)
fmax=$(grep -E 'Max frequency' "$outdir/nextpnr.log" | tail -n 1 | sed 's/.*: //')
if [[ -z $lc ]]; then
  echo "gyro_synth_lc: no ICESTORM_LC line in $outdir/nextpnr.log" >&2
  exit 1
fi
echo "gyro_ctrl + spi_master + gyro_accum: $lc logic cells (limit $max_lc), $fmax"
if (( lc > max_lc )); then
  echo "gyro_synth_lc: $lc logic cells exceed the limit of $max_lc" >&2
  exit 1
fi
