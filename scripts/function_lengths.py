#!/usr/bin/env python3
"""No function over 60 lines in host/ and sim/, but for those on an allow-list that can only shrink.

  scripts/function_lengths.py                      check host/ and sim/ against
                                                   tests/function_length_allow.txt (the CTest
                                                   function_lengths)
  scripts/function_lengths.py --list               print every function over the limit, in the
                                                   allow-list's format, longest first
  scripts/function_lengths.py --root DIR --allow FILE [--dirs host sim] [--limit 60]

Lengths come from universal-ctags (Debian package universal-ctags): end - line + 1 of each
function definition. The allow-list holds one line per function, `<length> <path> <name>`, the
name qualified by its scope (`omniloc::World::step`); anonymous namespaces, which ctags names
`__anon<hash>` differently in each file, are written `(anonymous)`. '#' starts a comment.

Exit 1 when a function over the limit is not listed, when a listed one grew past its length, or
when an entry is stale (the function is now shorter than listed, or gone): lower or remove the
entry, so the list only ever shrinks. Exit 2 when ctags is missing or the allow-list is malformed.
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
from collections import defaultdict

LIMIT = 60
ANON = re.compile(r"__anon[0-9a-fA-F]+")


def fail(message, code):
    print("function_lengths: " + message, file=sys.stderr)
    sys.exit(code)


def qualified_name(tag):
    """The function's name with its scope, anonymous namespaces normalised to (anonymous)."""
    scope = tag.get("scope", "")
    name = scope + "::" + tag["name"] if scope else tag["name"]
    return ANON.sub("(anonymous)", name)


def measure(root, dirs):
    """Every C++ function definition under root/dirs as (path, name, length)."""
    ctags = shutil.which("ctags")
    if ctags is None:
        fail("error: ctags not found (Debian package universal-ctags; make deps installs it)", 2)
    existing = [d for d in dirs if os.path.isdir(os.path.join(root, d))]
    if not existing:
        fail("error: none of %s under %s" % (", ".join(dirs), root), 2)
    command = [ctags, "--languages=C++", "--kinds-C++=f", "--fields=+ne", "--output-format=json",
               "--sort=no", "-f", "-", "-R"] + existing
    try:
        run = subprocess.run(command, cwd=root, capture_output=True, text=True, check=False)
    except OSError as error:
        fail("error: cannot run %s: %s" % (ctags, error), 2)
    if run.returncode != 0 or (run.stdout.strip() and not run.stdout.lstrip().startswith("{")):
        fail("error: %s is not universal-ctags with JSON output (Debian package universal-ctags): "
             "%s" % (ctags, run.stderr.strip() or run.stdout[:200]), 2)
    functions = []
    for line in run.stdout.splitlines():
        if not line.strip():
            continue
        tag = json.loads(line)
        if tag.get("_type") != "tag" or "end" not in tag or "line" not in tag:
            continue
        path = tag["path"].replace(os.sep, "/")
        functions.append((path, qualified_name(tag), tag["end"] - tag["line"] + 1))
    return functions


def read_allow_list(path):
    """{(path, name): [lengths]} from the allow-list (a name may be listed twice for overloads)."""
    allowed = defaultdict(list)
    try:
        with open(path, encoding="utf-8") as stream:
            lines = stream.readlines()
    except OSError as error:
        fail("error: cannot read the allow-list %s: %s" % (path, error), 2)
    for number, raw in enumerate(lines, 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        fields = line.split(None, 2)
        if len(fields) != 3 or not fields[0].isdigit():
            fail("error: %s:%d: expected `<length> <path> <name>`, got %r" % (path, number,
                                                                              raw.strip()), 2)
        allowed[(fields[1], ANON.sub("(anonymous)", fields[2]))].append(int(fields[0]))
    return allowed


def check(functions, allowed, limit, allow_path):
    """The problems, as lines; empty when the tree and the allow-list agree."""
    measured = defaultdict(list)
    for path, name, length in functions:
        measured[(path, name)].append(length)
    problems = []
    for key in sorted(set(measured) | set(allowed)):
        path, name = key
        # Overloads share a name: pair the longest with the largest listed length, and so on.
        actual = sorted(measured.get(key, []), reverse=True)
        listed = sorted(allowed.get(key, []), reverse=True)
        over = [n for n in actual if n > limit]
        for i, length in enumerate(over):
            if i >= len(listed):
                problems.append("%s %s is %d lines, over the limit of %d and not on the allow-list "
                                "%s: split it into named steps" % (path, name, length, limit,
                                                                   allow_path))
            elif length > listed[i]:
                problems.append("%s %s grew to %d lines, longer than its allow-list entry of %d: "
                                "shorten it (the allow-list can only shrink)" % (path, name, length,
                                                                                 listed[i]))
            elif length < listed[i]:
                problems.append("%s %s is now %d lines, shorter than its allow-list entry of %d: "
                                "lower the entry to %d in %s" % (path, name, length, listed[i],
                                                                 length, allow_path))
        for length in listed[len(over):]:
            now = ("gone" if not actual else "now %d lines, within the limit of %d" %
                   (max(actual), limit))
            problems.append("%s %s is listed at %d lines but is %s: remove the entry from %s" %
                            (path, name, length, now, allow_path))
    return problems


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    here = os.path.dirname(os.path.abspath(__file__))
    parser.add_argument("--root", default=os.path.dirname(here), help="the tree (default: the repo)")
    parser.add_argument("--allow", help="the allow-list (default: ROOT/tests/function_length_allow.txt)")
    parser.add_argument("--dirs", nargs="+", default=["host", "sim"], help="directories under ROOT")
    parser.add_argument("--limit", type=int, default=LIMIT, help="the longest allowed function")
    parser.add_argument("--list", action="store_true", help="print the functions over the limit")
    args = parser.parse_args()
    root = os.path.abspath(args.root)
    functions = measure(root, args.dirs)
    over = sorted((f for f in functions if f[2] > args.limit), key=lambda f: (-f[2], f[0], f[1]))
    if args.list:
        for path, name, length in over:
            print("%d %s %s" % (length, path, name))
        return 0
    allow_path = args.allow or os.path.join(root, "tests", "function_length_allow.txt")
    problems = check(functions, read_allow_list(allow_path), args.limit, allow_path)
    if problems:
        for problem in problems:
            print("function_lengths: " + problem, file=sys.stderr)
        print("function_lengths: %d problem(s) with functions over %d lines in %s" %
              (len(problems), args.limit, " and ".join(args.dirs)), file=sys.stderr)
        return 1
    if over:
        path, name, length = over[0]
        print("function_lengths: %d functions over %d lines, all on the allow-list (longest: %d "
              "lines, %s %s)" % (len(over), args.limit, length, path, name))
    else:
        print("function_lengths: %d functions, none over %d lines" % (len(functions), args.limit))
    return 0


if __name__ == "__main__":
    sys.exit(main())
