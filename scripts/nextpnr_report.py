#!/usr/bin/env python3
"""Print Fmax and utilisation from a nextpnr --report JSON; exit 1 when a clock misses --min-mhz."""
import argparse
import json
import sys


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("report")
    parser.add_argument("--min-mhz", type=float, default=0.0)
    args = parser.parse_args()
    try:
        with open(args.report) as f:
            report = json.load(f)
    except (OSError, json.JSONDecodeError) as exc:
        print(f"nextpnr_report: error: cannot read {args.report}: {exc}", file=sys.stderr)
        return 2
    ok = True
    for clock, fmax in sorted(report.get("fmax", {}).items()):
        achieved, constraint = fmax["achieved"], fmax["constraint"]
        verdict = "ok" if achieved >= max(constraint, args.min_mhz) else "FAILS"
        ok &= verdict == "ok"
        print(f"timing: clock {clock}: achieved {achieved:.1f} MHz, constraint {constraint:.1f} MHz: {verdict}")
    if not report.get("fmax"):
        print("nextpnr_report: error: the report has no clock", file=sys.stderr)
        ok = False
    util = report.get("utilization", {})
    for cell in ("ICESTORM_LC", "ICESTORM_RAM", "ICESTORM_SPRAM", "SB_IO", "ICESTORM_DSP", "SB_GB", "ICESTORM_PLL"):
        if cell in util:
            used, avail = util[cell]["used"], util[cell]["available"]
            print(f"utilisation: {cell:15s} {used:5d} / {avail:5d} ({100.0 * used / avail:.1f} %)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
