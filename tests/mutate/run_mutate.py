#!/usr/bin/env python3
"""Mutation check of the RTL: does the test suite notice a wrong design?

Each mutation of tests/mutate/mutations.txt is a named one-line change of one RTL file (a
substring that must occur exactly once in the file, and its replacement). It is applied to a
temporary copy of rtl/ (the repository is never edited), then its checks run against that copy in
order until one fails: the mutation is KILLED by that check. A mutation that passes all of its
checks SURVIVED (the tests cannot tell it from the real design). A mutation whose copy a check
cannot build (yosys cannot read it, the testbench does not verilate or compile) DOES NOT BUILD: it
tests nothing, and the run goes on with the next one. Exit status: 0 when every mutation was
killed, 1 when one survived (or a check could not decide, e.g. a timeout), 2 on a usage error, a
mutation that does not apply (its pattern missing or not unique) or one that does not build.

Lint is not a build failure here: the testbenches of the mutated copy are verilated with -Wall
-Wno-fatal (CMake OMNILOC_VERILATOR_LINT_FATAL=OFF, that tree only), so a mutant that, say, leaves
a signal unused (UNUSEDSIGNAL) is built and tested like any other; its warnings are named on its line of
the report ("lint: UNUSEDSIGNAL"). The normal build and `make lint` keep -Wall fatal for rtl/.

Checks:
  formal:NAME          the CTest test formal_NAME of the build tree (tests/formal, tests/link,
                       tests/rtl/gyro), its command taken from `ctest --show-only=json-v1` with the
                       rtl/ paths pointed at the mutated copy
  rtl:TARGET:FILTER    the GoogleTest executable TARGET (tb_encoder_modules, tb_link_modules,
                       tb_encoder_core, tb_gyro_ctrl), built in a second CMake tree whose
                       OMNILOC_RTL_DIR is the mutated copy, run with --gtest_filter=FILTER

Before the mutations, every check used runs once on the unmutated copy (the baseline): a check
that fails there would kill every mutation and prove nothing, so the run stops.

usage: run_mutate.py --build BUILD [--work DIR] [--list-file FILE] [--fast] [--only NAME[,NAME...]]
                     [--no-baseline] [--formal-only | --rtl-only] [--list] [--jobs N]
  --fast   only the mutations marked `fast: yes` and only their formal checks (the subset that
           `make test` runs as the CTest test mutate_fast, label mutate)
  --formal-only  the mutations that have formal checks, with only those checks
  --rtl-only     the mutations that have cycle-test checks, with only those checks (every such
                 mutant is then built, which a formal check killing it first would skip)
"""

import argparse
import filecmp
import json
import os
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.dirname(os.path.dirname(HERE))
RTL = os.path.join(SRC, "rtl")
KEYS = ("name", "file", "find", "replace", "checks", "fast", "why")


def die(msg, code=2):
    print(f"run_mutate: {msg}", file=sys.stderr)
    sys.exit(code)


def parse_mutations(path):
    """Blocks of `key: value` lines separated by blank lines; '#' lines are comments."""
    muts, cur, lineno_of = [], {}, {}
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    for n, line in enumerate(lines + [""], 1):
        if line.startswith("#"):
            continue
        if not line.strip():
            if cur:
                muts.append(cur)
                cur = {}
            continue
        m = re.match(r"^([a-z]+): ?(.*)$", line)
        if not m or m.group(1) not in KEYS:
            die(f"{path}:{n}: expected 'key: value' with key one of {', '.join(KEYS)}: {line!r}")
        if m.group(1) in cur:
            die(f"{path}:{n}: key {m.group(1)} twice in one mutation")
        if not cur:
            cur["line"] = n
        cur[m.group(1)] = m.group(2)
    names = set()
    for mu in muts:
        for k in ("name", "file", "find", "replace", "checks"):
            if k not in mu:
                die(f"{path}:{mu['line']}: mutation without '{k}'")
        if mu["name"] in names:
            die(f"{path}:{mu['line']}: mutation name {mu['name']} twice")
        names.add(mu["name"])
        if mu["find"] == mu["replace"]:
            die(f"{path}:{mu['line']}: {mu['name']}: replace is the same as find")
        mu["checks"] = mu["checks"].split()
        mu["fast"] = mu.get("fast", "no") == "yes"
        for c in mu["checks"]:
            if not re.match(r"^(formal:[A-Za-z0-9_]+|rtl:[A-Za-z0-9_]+:\S+)$", c):
                die(f"{path}:{mu['line']}: {mu['name']}: bad check {c!r}")
    return muts


def apply(mu, text):
    """The mutated text; fails loudly unless the pattern occurs exactly once."""
    n = text.count(mu["find"])
    if n != 1:
        die(f"mutation {mu['name']}: pattern occurs {n} times in {mu['file']} (must be exactly once): "
            f"{mu['find']!r}")
    return text.replace(mu["find"], mu["replace"])


def formal_tests(build):
    out = subprocess.run(["ctest", "--test-dir", build, "--show-only=json-v1", "-L", "formal"],
                         capture_output=True, text=True, check=True).stdout
    tests = {}
    for t in json.loads(out)["tests"]:
        env = {}
        timeout = 300
        for p in t.get("properties", []):
            if p["name"] == "ENVIRONMENT":
                env.update(v.split("=", 1) for v in p["value"])
            if p["name"] == "TIMEOUT":
                timeout = int(p["value"])
        tests[t["name"]] = (t["command"], env, timeout)
    return tests


class Runner:
    def __init__(self, args):
        self.build = os.path.abspath(args.build)
        self.work = os.path.abspath(args.work or os.path.join(self.build, "mutate"))
        self.copy = os.path.join(self.work, "rtl")
        self.mbuild = os.path.join(self.work, "build")
        self.jobs = args.jobs
        self.formal = formal_tests(self.build)
        self.configured = False
        self.built = {}
        self.base_secs = {}

    def fresh_copy(self):
        """The copy made equal to rtl/. A file whose content differs (e.g. left mutated by an
        earlier, interrupted run) is written now (shutil.copyfile, not copy2: copied back with
        rtl/'s older mtime it would leave the testbenches built from the mutated file looking up to
        date); a file already equal keeps its mtime, so that a second run does not rebuild every
        testbench from scratch (there may be no ccache). Files gone from rtl/ are removed."""
        want = set()
        for root, _, files in os.walk(RTL):
            for f in files:
                rel = os.path.relpath(os.path.join(root, f), RTL)
                want.add(rel)
                src, dst = os.path.join(RTL, rel), os.path.join(self.copy, rel)
                if not (os.path.isfile(dst) and filecmp.cmp(src, dst, shallow=False)):
                    os.makedirs(os.path.dirname(dst), exist_ok=True)
                    shutil.copyfile(src, dst)
        for root, _, files in os.walk(self.copy):
            for f in files:
                if os.path.relpath(os.path.join(root, f), self.copy) not in want:
                    os.remove(os.path.join(root, f))

    def write(self, rel, text):
        # rel is rtl/..., the copy is rtl/ itself
        path = os.path.join(self.copy, os.path.relpath(rel, "rtl"))
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)

    def configure(self):
        if self.configured:
            return
        cache = open(os.path.join(self.build, "CMakeCache.txt"), encoding="utf-8").read()
        # Lint warnings of a mutant are not fatal in this tree (see the top of this file).
        args = ["cmake", "-S", SRC, "-B", self.mbuild, "-DOMNILOC_RTL_DIR=" + self.copy,
                "-DOMNILOC_VERILATOR_LINT_FATAL=OFF"]
        for var in ("CMAKE_BUILD_TYPE", "CMAKE_GENERATOR", "CMAKE_C_COMPILER_LAUNCHER",
                    "CMAKE_CXX_COMPILER_LAUNCHER"):
            m = re.search(rf"^{var}:\w+=(.*)$", cache, re.M)
            if m and m.group(1):
                args.append(f"-{'G' if var == 'CMAKE_GENERATOR' else 'D' + var + '='}{m.group(1)}")
        r = subprocess.run(args, capture_output=True, text=True)
        if r.returncode != 0:
            print(r.stdout[-3000:], r.stderr[-3000:])
            die("configuring the mutation build tree failed")
        self.configured = True

    def run_check(self, check, tag, timeout=None):
        """(passed, seconds, detail, kind, lint): passed None = undecided (timeout); kind "build"
        = the copy could not be built for this check (not lint), "fail" = the check failed,
        "timeout", or "" = passed; lint = the Verilator warning codes of the testbench build."""
        lint = []
        start = time.monotonic()
        kind = check.split(":")[0]
        log = os.path.join(self.work, "logs", f"{tag}.{check.replace(':', '_').replace('*', 'x')}.log")
        os.makedirs(os.path.dirname(log), exist_ok=True)
        if kind == "formal":
            name = "formal_" + check.split(":")[1]
            if name not in self.formal:
                die(f"no CTest test {name} in {self.build} (ctest -L formal -N)")
            cmd, env, ctest_timeout = self.formal[name]
            outdir = os.path.join(self.work, "formal", tag)
            cmd = [a.replace(RTL + "/", self.copy + "/").replace(RTL + " ", self.copy + " ")
                    .replace(os.path.join(self.build, "formal"), outdir) for a in cmd]
            if any(RTL + "/" in a for a in cmd):
                die(f"{name}: an rtl/ path was not redirected to the copy: {cmd}")
            full_env = dict(os.environ, **env)
            to = timeout or ctest_timeout
        else:
            _, target, filt = check.split(":", 2)
            self.configure()
            b = subprocess.run(["cmake", "--build", self.mbuild, "--target", target, "-j", str(self.jobs)],
                               capture_output=True, text=True)
            blog = log[:-len(".log")] + ".build.log"
            with open(blog, "w") as f:
                f.write(b.stdout + b.stderr)
            lint = sorted(set(re.findall(r"%Warning-([A-Z0-9_]+):", b.stdout + b.stderr)))
            if b.returncode != 0:
                # Warnings are not fatal in this tree: the first error says why it did not build.
                err = re.search(r"^.*(%Error.*|error:.*)$", b.stdout + b.stderr, re.M)
                why = err.group(1).strip()[:160] if err else f"exit {b.returncode}"
                return False, time.monotonic() - start, f"{why} (log {blog})", "build", lint
            exe = self.find_exe(target)
            cmd = [exe, f"--gtest_filter={filt}"]
            full_env = dict(os.environ)
            to = timeout or 600
        try:
            r = subprocess.run(cmd, capture_output=True, text=True, env=full_env, timeout=to,
                               cwd=self.mbuild if kind == "rtl" else self.work)
        except subprocess.TimeoutExpired:
            return None, time.monotonic() - start, f"timeout after {to} s", "timeout", lint
        with open(log, "w") as f:
            f.write(r.stdout + r.stderr)
        secs = time.monotonic() - start
        if r.returncode == 0:
            return True, secs, "", "", lint
        text = r.stdout + r.stderr
        if kind == "formal" and "yosys failed" in text:
            return False, secs, f"yosys failed (log {log})", "build", lint
        if kind == "rtl" and "[  FAILED  ]" not in text:
            # A crash or abort of the testbench: not a build failure, not a clean kill either.
            return None, secs, f"exit {r.returncode} without a failed test (log {log})", "timeout", lint
        detail = ""
        if kind == "formal":
            m = re.findall(r"FORMAL \S+: (\w+ depth \d+) FAILED", text)
            detail = m[-1] if m else "failed"
            a = re.search(r"Assert failed in \S+: (\S+)", text) or re.search(r"(Unreached cover statement.*)", text)
            if a:
                detail += " at " + os.path.basename(a.group(1).strip())
        else:
            m = re.findall(r"\[  FAILED  \] (\S+) \(", text)
            detail = ", ".join(m[:3]) if m else "failed"
        return False, secs, detail, "fail", lint

    def find_exe(self, target):
        if target not in self.built:
            for root, _, files in os.walk(self.mbuild):
                if target in files and os.access(os.path.join(root, target), os.X_OK):
                    self.built[target] = os.path.join(root, target)
                    break
            else:
                die(f"built {target} but found no executable of that name under {self.mbuild}")
        return self.built[target]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", required=True)
    ap.add_argument("--work")
    ap.add_argument("--list-file", default=os.path.join(HERE, "mutations.txt"))
    ap.add_argument("--fast", action="store_true")
    ap.add_argument("--only")
    ap.add_argument("--no-baseline", action="store_true")
    ap.add_argument("--formal-only", action="store_true")
    ap.add_argument("--rtl-only", action="store_true")
    ap.add_argument("--list", action="store_true")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()

    muts = parse_mutations(args.list_file)
    # Every pattern must apply to the tree as it is, before anything runs.
    originals = {}
    for mu in muts:
        path = os.path.join(SRC, mu["file"])
        if not mu["file"].startswith("rtl/") or not os.path.isfile(path):
            die(f"mutation {mu['name']}: {mu['file']} is not a file under rtl/")
        originals.setdefault(mu["file"], open(path, encoding="utf-8").read())
        apply(mu, originals[mu["file"]])
    print(f"{len(muts)} mutations in {os.path.relpath(args.list_file, SRC)}, every pattern found exactly once")
    if args.only:
        want = args.only.split(",")
        unknown = set(want) - {m["name"] for m in muts}
        if unknown:
            die(f"unknown mutation(s): {', '.join(sorted(unknown))}")
        muts = [m for m in muts if m["name"] in want]
    if args.fast:
        muts = [m for m in muts if m["fast"]]
        for m in muts:
            m["checks"] = [c for c in m["checks"] if c.startswith("formal:")]
            if not m["checks"]:
                die(f"mutation {m['name']} is fast but has no formal check")
    if args.formal_only:
        muts = [m for m in muts if any(c.startswith("formal:") for c in m["checks"])]
        for m in muts:
            m["checks"] = [c for c in m["checks"] if c.startswith("formal:")]
    if args.rtl_only:
        if args.formal_only or args.fast:
            die("--rtl-only goes with neither --formal-only nor --fast")
        muts = [m for m in muts if any(c.startswith("rtl:") for c in m["checks"])]
        for m in muts:
            m["checks"] = [c for c in m["checks"] if c.startswith("rtl:")]
    if args.list:
        for m in muts:
            print(f"  {m['name']:<34} {m['file']:<28} {' '.join(m['checks'])}")
        return 0

    runner = Runner(args)
    os.makedirs(runner.work, exist_ok=True)
    runner.fresh_copy()
    t0 = time.monotonic()

    if not args.no_baseline:
        used = []
        for m in muts:
            used += [c for c in m["checks"] if c not in used]
        print(f"baseline: {len(used)} checks on the unmutated copy")
        for c in used:
            ok, secs, detail, _, lint = runner.run_check(c, "baseline")
            runner.base_secs[c] = secs
            note = f" [lint: {' '.join(lint)}: rtl/ itself is not lint-clean]" if lint else ""
            print(f"  {c:<50} {'passed' if ok else 'FAILED ' + detail} ({secs:.1f} s){note}", flush=True)
            if not ok:
                die(f"check {c} fails on the unmutated design: fix it before mutating", 1)

    killed, survived, undecided, unbuilt = [], [], [], []
    for i, mu in enumerate(muts, 1):
        runner.write(mu["file"], apply(mu, originals[mu["file"]]))
        result, by, lints = None, [], []
        start = time.monotonic()
        for c in mu["checks"]:
            base = runner.base_secs.get(c)
            ok, secs, detail, kind, lint = runner.run_check(
                c, mu["name"], timeout=None if base is None else int(max(60, 5 * base)))
            lints += [w for w in lint if w not in lints]
            if kind == "build":
                result = "unbuilt"
                by = [f"{c}: {detail}"]
                break
            if ok is None:
                by.append(f"{c}: {detail}")
                result = result or "undecided"
                continue
            if not ok:
                result = "killed"
                by = [f"{c} ({detail})"]
                break
        runner.write(mu["file"], originals[mu["file"]])
        secs = time.monotonic() - start
        note = f" (lint: {' '.join(lints)})" if lints else ""
        if result == "unbuilt":
            unbuilt.append(mu["name"])
            print(f"[{i:2}/{len(muts)}] {mu['name']:<34} DOES NOT BUILD {by[0]} [{secs:.0f} s]", flush=True)
        elif result == "killed":
            killed.append(mu["name"])
            print(f"[{i:2}/{len(muts)}] {mu['name']:<34} killed   by {by[0]}{note} [{secs:.0f} s]", flush=True)
        elif result == "undecided":
            undecided.append(mu["name"])
            print(f"[{i:2}/{len(muts)}] {mu['name']:<34} UNDECIDED {'; '.join(by)}{note} [{secs:.0f} s]", flush=True)
        else:
            survived.append(mu["name"])
            print(f"[{i:2}/{len(muts)}] {mu['name']:<34} SURVIVED {' '.join(mu['checks'])} all passed"
                  f"{note} [{secs:.0f} s]", flush=True)

    n = len(muts)
    print(f"{len(killed)} of {n} mutations killed ({time.monotonic() - t0:.0f} s)")
    if survived:
        print("survived: " + ", ".join(survived))
    if undecided:
        print("undecided: " + ", ".join(undecided))
    if unbuilt:
        print("does not build (not lint: fix or drop the mutation): " + ", ".join(unbuilt))
        return 2
    return 0 if len(killed) == n else 1


if __name__ == "__main__":
    sys.exit(main())
