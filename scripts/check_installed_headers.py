#!/usr/bin/env python3
"""The installed API is closed and self-contained.

The CTest installed_headers runs

    check_installed_headers.py --include-dir host/include --list "a.hpp,b.hpp,..." [--compile]

with the list CMake installs (OMNILOC_PUBLIC_HEADERS, host/CMakeLists.txt), and checks that
  1. the list is exactly the files in host/include/omniloc/ (a header there is installed, and an
     installed header is there: internals live in host/src/include/, docs/ARCHITECTURE.md);
  2. every `#include "omniloc/..."` or `#include <omniloc/...>` of an installed header names an
     installed header (an installed header that includes an internal one, such as
     omniloc/detail/config_reader.hpp or omniloc/calibration.hpp, fails);
  3. with --compile: each installed header compiles on its own (c++ -std=c++20 -fsyntax-only) with
     only the installed headers on the include path (copied to a temporary directory) and the
     flags of the packages omniloc.pc requires (pkg-config --cflags eigen3 opencv4 nlohmann_json).

    check_installed_headers.py --installed PREFIX/include/omniloc

checks 2 on an installed tree (scripts/check_install.sh runs it after `cmake --install`).

    check_installed_headers.py --self-test

shows that the checks fail when they should: a fixture with an installed header that includes an
uninstalled one, a header missing from the list, a header that does not compile alone, and a clean
fixture that must pass.
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

INCLUDE_RE = re.compile(r'^\s*#\s*include\s*[<"](omniloc/[^>"]+)[>"]', re.MULTILINE)
PKG_REQUIRES = ["eigen3", "opencv4", "nlohmann_json"]


def omniloc_includes(path):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    # Comments may mention headers; only directives count (a // or /* */ before # is not one).
    return INCLUDE_RE.findall(text)


def check_closed(include_root, installed):
    """Errors for each include of an installed header that is not installed."""
    errors = []
    installed_set = set(installed)
    for name in sorted(installed):
        path = os.path.join(include_root, "omniloc", name)
        if not os.path.isfile(path):
            continue  # reported by check_list_matches_dir
        for inc in omniloc_includes(path):
            target = inc[len("omniloc/"):]
            if target not in installed_set:
                errors.append(f"omniloc/{name} includes {inc}, which is not installed")
    return errors


def check_list_matches_dir(include_root, listed):
    errors = []
    on_disk = {f for f in os.listdir(os.path.join(include_root, "omniloc")) if f.endswith((".hpp", ".h"))}
    for f in sorted(on_disk - set(listed)):
        errors.append(f"{include_root}/omniloc/{f} is not in the install list (install it, or move it "
                      "to host/src/include/ if it is internal)")
    for f in sorted(set(listed) - on_disk):
        errors.append(f"omniloc/{f} is in the install list but not in {include_root}/omniloc/")
    return errors


def package_cflags(cflags):
    if cflags is not None:
        return cflags.split()
    try:
        out = subprocess.run(["pkg-config", "--cflags"] + PKG_REQUIRES, check=True,
                             capture_output=True, text=True).stdout
    except (OSError, subprocess.CalledProcessError) as e:
        raise SystemExit(f"installed_headers: pkg-config --cflags {' '.join(PKG_REQUIRES)} failed: {e}")
    return out.split()


def check_compile(include_root, installed, cxx, cflags, jobs):
    """Each installed header alone, against a copy of the installed headers only."""
    errors = []
    with tempfile.TemporaryDirectory(prefix="omniloc-installed-headers-") as tmp:
        inc = os.path.join(tmp, "include")
        os.makedirs(os.path.join(inc, "omniloc"))
        for name in installed:
            shutil.copy(os.path.join(include_root, "omniloc", name), os.path.join(inc, "omniloc", name))

        def one(name):
            src = os.path.join(tmp, name.replace("/", "_") + ".cpp")
            with open(src, "w", encoding="utf-8") as f:
                f.write(f'#include "omniloc/{name}"\n')
            cmd = [cxx, "-std=c++20", "-fsyntax-only", "-I" + inc] + cflags + [src]
            r = subprocess.run(cmd, capture_output=True, text=True)
            if r.returncode != 0:
                first = "\n".join(r.stderr.splitlines()[:8])
                return f"omniloc/{name} does not compile on its own against the installed headers:\n{first}"
            return None

        with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
            for err in pool.map(one, sorted(installed)):
                if err:
                    errors.append(err)
    return errors


def run(include_root, listed, compile_, cxx, cflags, jobs):
    errors = check_list_matches_dir(include_root, listed) if listed is not None else []
    installed = listed if listed is not None else sorted(
        f for f in os.listdir(os.path.join(include_root, "omniloc")) if f.endswith((".hpp", ".h")))
    errors += check_closed(include_root, installed)
    if compile_ and not errors:
        errors += check_compile(include_root, installed, cxx, package_cflags(cflags), jobs)
    return installed, errors


def self_test(cxx):
    def fixture(tmp, files):
        root = os.path.join(tmp, "include")
        shutil.rmtree(root, ignore_errors=True)
        os.makedirs(os.path.join(root, "omniloc"))
        for name, text in files.items():
            with open(os.path.join(root, "omniloc", name), "w", encoding="utf-8") as f:
                f.write(text)
        return root

    cases = [
        # (what, files, install list, compile, expected error fragment or None)
        ("clean", {"a.hpp": '#pragma once\n#include "omniloc/b.hpp"\ninline int a() { return b(); }\n',
                   "b.hpp": "#pragma once\ninline int b() { return 1; }\n"},
         ["a.hpp", "b.hpp"], True, None),
        ("includes an uninstalled header",
         {"a.hpp": '#pragma once\n#include "omniloc/detail/config_reader.hpp"\n'},
         ["a.hpp"], False, "includes omniloc/detail/config_reader.hpp, which is not installed"),
        ("includes an uninstalled header, angle brackets",
         {"a.hpp": "#pragma once\n#include <omniloc/calibration.hpp>\n"},
         ["a.hpp"], False, "includes omniloc/calibration.hpp, which is not installed"),
        ("a header not in the install list",
         {"a.hpp": '#pragma once\n#include "omniloc/b.hpp"\n', "b.hpp": "#pragma once\n"},
         ["a.hpp"], False, "b.hpp is not in the install list"),
        ("a listed header that does not exist",
         {"a.hpp": "#pragma once\n"}, ["a.hpp", "gone.hpp"], False,
         "omniloc/gone.hpp is in the install list but not in"),
        ("a comment is not an include",
         {"a.hpp": "#pragma once\n// #include \"omniloc/detail/x.hpp\" (not a directive)\n"},
         ["a.hpp"], False, None),
        ("not self-contained",
         {"a.hpp": "#pragma once\ninline std::string a() { return {}; }\n"},
         ["a.hpp"], True, "does not compile on its own"),
    ]
    failed = 0
    with tempfile.TemporaryDirectory(prefix="omniloc-installed-headers-selftest-") as tmp:
        for what, files, listed, compile_, expected in cases:
            root = fixture(tmp, files)
            _, errors = run(root, listed, compile_, cxx, "", 1)
            text = "\n".join(errors)
            ok = (not errors) if expected is None else (expected in text)
            print(f"installed_headers self-test: {'ok  ' if ok else 'FAIL'} {what}"
                  + ("" if ok else f" (errors: {text or 'none'})"))
            failed += not ok
    if failed:
        print(f"installed_headers self-test: FAILED: {failed} case(s)", file=sys.stderr)
        return 1
    print("installed_headers self-test: every fixture gave the expected verdict")
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--include-dir", help="the source include root (host/include)")
    ap.add_argument("--list", help="the installed headers, ','- or ';'-separated, relative to omniloc/")
    ap.add_argument("--installed", help="an installed PREFIX/include/omniloc to check")
    ap.add_argument("--compile", action="store_true", help="compile each header on its own")
    ap.add_argument("--cxx", default=os.environ.get("CXX", "c++"))
    ap.add_argument("--cflags", help="flags for the required packages (default: pkg-config)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--self-test", action="store_true")
    a = ap.parse_args()

    if a.self_test:
        return self_test(a.cxx)
    if a.installed:
        root = os.path.dirname(os.path.abspath(a.installed.rstrip("/")))
        installed, errors = run(root, None, a.compile, a.cxx, a.cflags, a.jobs)
    elif a.include_dir and a.list is not None:
        listed = [x for x in re.split(r"[;,]", a.list) if x]
        installed, errors = run(a.include_dir, listed, a.compile, a.cxx, a.cflags, a.jobs)
    else:
        ap.error("give --include-dir and --list, --installed, or --self-test")
    for e in errors:
        print(f"installed_headers: {e}", file=sys.stderr)
    if errors:
        print(f"installed_headers: FAILED ({len(errors)} problem(s))", file=sys.stderr)
        return 1
    print(f"installed_headers: OK: {len(installed)} installed headers include only installed headers"
          + (" and each compiles on its own" if a.compile else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
