#!/usr/bin/env bash
# Portability check: the same RTL through yosys synth_xilinx for a Zynq-7010 (xc7z010, the FPGA of
# the paper's NI myRIO) at the paper's clock (PAPER_CLOCK_HZ of common/regmap.json, 40 MHz), with the
# utilisation against the device.
# Usage: scripts/synth_xilinx.sh [BUILD_DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(realpath -m "${1:-build}")
out="$build/zynq7010"
mkdir -p "$out"
cd "$root"
target_hz=$(sed -n 's/^`define OMNILOC_PAPER_CLOCK_HZ \([0-9]*\)$/\1/p' rtl/include/omniloc_regs.vh)
[ -n "$target_hz" ] || { echo "synth_xilinx: error: no OMNILOC_PAPER_CLOCK_HZ in rtl/include/omniloc_regs.vh" >&2; exit 1; }
mapfile -t sources < <(ls rtl/*.v rtl/gyro/*.v | grep -v '_top\.v$' ; echo rtl/omniloc_top.v)
yosys -q -l "$out/yosys.log" -p "read_verilog -Irtl/include ${sources[*]}; chparam -set CLK_HZ $target_hz omniloc_top; synth_xilinx -family xc7 -top omniloc_top; tee -o $out/stat.txt stat"
python3 - "$out/stat.txt" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
# The last "Number of cells" block is the design total; count LUTs, flip-flops, carry and RAM cells.
cells = {}
for name, count in re.findall(r"^\s+(\S+)\s+(\d+)\s*$", text, re.M):
    cells[name] = int(count)
luts = sum(v for k, v in cells.items() if re.fullmatch(r"LUT[1-6]", k))
ffs = sum(v for k, v in cells.items() if re.fullmatch(r"FD[A-Z]*", k))
carry = cells.get("CARRY4", 0)
brams = sum(v for k, v in cells.items() if k.startswith("RAMB"))
if luts == 0 or ffs == 0:
    print("synth_xilinx: error: no LUTs or flip-flops in the statistics", file=sys.stderr)
    sys.exit(1)
print(f"zynq-7010 utilisation: LUT {luts} / 17600 ({100 * luts / 17600:.1f} %), "
      f"FF {ffs} / 35200 ({100 * ffs / 35200:.1f} %), CARRY4 {carry}, BRAM {brams}")
PY
