#!/usr/bin/env python3
"""Print Fmax and utilisation from a nextpnr --report JSON; exit 1 when a clock misses --min-mhz
(the requirement; without it, the constraint nextpnr placed for) or the design uses more than
--max-lcs logic cells."""
import argparse
import json
import re
import sys


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("report")
    parser.add_argument("--min-mhz", type=float, default=0.0)
    parser.add_argument("--max-lcs", type=int, default=0, help="fail above this many ICESTORM_LC (0: no limit)")
    parser.add_argument("--modules", help="yosys `stat` output of a synth_ice40 -noflatten run")
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
        required = args.min_mhz if args.min_mhz > 0 else constraint
        verdict = "ok" if achieved >= required else "FAILS"
        ok &= verdict == "ok"
        goal = "met" if achieved >= constraint else "not met"
        print(f"timing: clock {clock}: achieved {achieved:.1f} MHz, required {required:.1f} MHz: {verdict}; "
              f"placed for {constraint:.1f} MHz: {goal}")
    if not report.get("fmax"):
        print("nextpnr_report: error: the report has no clock", file=sys.stderr)
        ok = False
    util = report.get("utilization", {})
    for cell in ("ICESTORM_LC", "ICESTORM_RAM", "ICESTORM_SPRAM", "SB_IO", "ICESTORM_DSP", "SB_GB", "ICESTORM_PLL"):
        if cell in util:
            used, avail = util[cell]["used"], util[cell]["available"]
            print(f"utilisation: {cell:15s} {used:5d} / {avail:5d} ({100.0 * used / avail:.1f} %)")
            if cell == "ICESTORM_LC" and args.max_lcs > 0:
                verdict = "ok" if used <= args.max_lcs else "FAILS"
                ok &= verdict == "ok"
                print(f"utilisation: {used} logic cells, allowed {args.max_lcs}: {verdict}")
    if args.modules:
        ok &= print_modules(args.modules)
    return 0 if ok else 1


def short_name(name):
    """uart_rx for $paramod$<hash>\\uart_rx or $paramod\\frame_tx\\MAX_BODY_BYTES=..."""
    parts = name.split("\\")
    return parts[1] if name.startswith("$paramod") and len(parts) > 1 else name


def print_modules(path):
    """Per-module cells from yosys `stat` of a -noflatten run: LUT4, flip-flops and carries of one
    instance (its own cells, not its submodules') and of all its instances in the design."""
    try:
        text = open(path).read()
    except OSError as exc:
        print(f"nextpnr_report: error: cannot read {path}: {exc}", file=sys.stderr)
        return False
    head, _, hierarchy = text.partition("=== design hierarchy ===")
    modules, current = {}, None
    for line in head.splitlines():
        m = re.match(r"^=== (\S+) ===", line)
        if m:
            current = short_name(m.group(1))
            modules[current] = {"lut": 0, "ff": 0, "carry": 0}
            continue
        m = re.match(r"^\s+(\d+)?\s*(SB_\w+)\s+(\d+)?$", line)
        if current and m:
            count = int(m.group(1) or m.group(3))
            cell = m.group(2)
            key = "lut" if cell == "SB_LUT4" else "ff" if cell.startswith("SB_DFF") else "carry" if cell == "SB_CARRY" else None
            if key:
                modules[current][key] += count
    # Instances in the whole design: the hierarchy tree's counts multiplied down its indentation.
    instances, stack = {}, []
    for line in hierarchy.splitlines():
        m = re.match(r"^( +)(\S+)\s+(\d+)$", line)
        if not m:
            if instances and line.strip().startswith("Number"):
                break
            continue
        depth = len(m.group(1))
        while stack and stack[-1][0] >= depth:
            stack.pop()
        total = int(m.group(3)) * (stack[-1][1] if stack else 1)
        name = short_name(m.group(2))
        instances[name] = instances.get(name, 0) + total
        stack.append((depth, total))
    print(f"utilisation per module: {'module':18s} inst | one instance: LUT4   FF carry | all: LUT4    FF carry")
    sums = {"lut": 0, "ff": 0, "carry": 0}
    for name in sorted(modules):
        c, n = modules[name], instances.get(name, 1)
        for k in sums:
            sums[k] += c[k] * n
        print(f"utilisation per module: {name:18s} {n:4d} |              {c['lut']:4d} {c['ff']:4d} {c['carry']:5d} |"
              f"     {c['lut'] * n:4d}  {c['ff'] * n:4d} {c['carry'] * n:5d}")
    print(f"utilisation per module: {'total':18s}      |                              |"
          f"     {sums['lut']:4d}  {sums['ff']:4d} {sums['carry']:5d}")
    return True


if __name__ == "__main__":
    sys.exit(main())
