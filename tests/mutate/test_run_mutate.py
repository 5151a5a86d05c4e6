#!/usr/bin/env python3
"""Self-test of the mutation harness (tests/mutate/run_mutate.py): does it tell a mutant that does
not build from one that is killed, and is a lint warning of a mutant (an unused signal) not taken
for a build failure?

It runs the harness on a list of its own (a temporary file, never mutations.txt) without baseline:
  broken_syntax   a mutant that is not Verilog (yosys cannot read it; Verilator stops with %Error)
                  -> must be reported DOES NOT BUILD, and the run must exit 2
  lint_unused     dec_x1_never_counts of mutations.txt, which leaves low_g[1] unused (Verilator
                  -Wall: UNUSEDSIGNAL; UNUSED before Verilator 5) -> must be killed, and with
                  --rtl its line must name the warning
Default: the formal checks only (a few seconds; CTest mutate_harness, label mutate). With --rtl,
the same two mutants against the cycle testbench tb_encoder_modules instead, built in WORK (point
--work at <build>/mutate to reuse the tree of `make mutate`, else it builds from scratch).

usage: test_run_mutate.py --build BUILD [--work DIR] [--rtl]
"""

import argparse
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))

LIST = """\
name: broken_syntax
file: rtl/quadrature_decoder.v
find: wire active = primed_q && en_i;
replace: wire active = primed_q && ;
checks: {check}
why: not Verilog: must be reported as not building

name: lint_unused
file: rtl/quadrature_decoder.v
find: (mode_i == `OMNILOC_CONTROL_DECODE_X1) ? (low_g == 2'd0)
replace: (mode_i == `OMNILOC_CONTROL_DECODE_X1) ? 1'b0
checks: {check}
why: leaves low_g[1] unused (Verilator UNUSEDSIGNAL): must build and be killed
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", required=True)
    ap.add_argument("--work")
    ap.add_argument("--rtl", action="store_true")
    args = ap.parse_args()
    check = "rtl:tb_encoder_modules:QuadratureDecoder.*" if args.rtl else "formal:quadrature_decoder"
    work = args.work or os.path.join(os.path.abspath(args.build), "mutate-harness")
    with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as f:
        f.write(LIST.format(check=check))
        listfile = f.name
    try:
        r = subprocess.run([sys.executable, os.path.join(HERE, "run_mutate.py"), "--build", args.build,
                            "--work", work, "--list-file", listfile, "--no-baseline"],
                           capture_output=True, text=True)
    finally:
        os.unlink(listfile)
    out = r.stdout + r.stderr
    print(out)
    lines = {l.split()[2]: l for l in r.stdout.splitlines() if l.startswith("[")}
    errors = []
    if r.returncode != 2:
        errors.append(f"exit status {r.returncode}, expected 2 (a mutation does not build)")
    if "DOES NOT BUILD" not in lines.get("broken_syntax", ""):
        errors.append("broken_syntax not reported DOES NOT BUILD")
    if " killed " not in lines.get("lint_unused", ""):
        errors.append("lint_unused not killed (a lint warning taken for a build failure?)")
    if args.rtl and "lint: UNUSED" not in lines.get("lint_unused", ""):
        errors.append("lint_unused's UNUSED warning not named on its line")
    if "does not build (not lint" not in r.stdout or "broken_syntax" not in r.stdout.split("does not build")[-1]:
        errors.append("the summary does not list broken_syntax as not building")
    for e in errors:
        print(f"test_run_mutate: FAILED: {e}", file=sys.stderr)
    if not errors:
        print("test_run_mutate: passed (" + ("cycle testbench" if args.rtl else "formal") + " checks)")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
