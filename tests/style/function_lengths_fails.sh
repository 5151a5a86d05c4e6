#!/usr/bin/env bash
# The CTest function_lengths_fails: scripts/function_lengths.py can fail. Runs it over the fixture
# tests/style/fixture/ (a 61-line function, a 60-line one, a 61-line one in an anonymous namespace)
# with allow-lists that match, are stale, or are exceeded, and without ctags on PATH.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
script="$here/../../scripts/function_lengths.py"
fixture="$here/fixture"
# The interpreter itself, not a shim (pyenv's need bash on PATH, which the no-ctags case empties).
python=$(python3 -c 'import sys; print(sys.executable)')
failures=0

# expect <name> <exit code> <allow-list> <text the output must hold>...
expect() {
  local name=$1 code=$2 allow=$3
  shift 3
  local out rc
  out=$("$python" "$script" --root "$fixture" --allow "$fixture/$allow" 2>&1)
  rc=$?
  if [ "$rc" -ne "$code" ]; then
    echo "FAIL $name: exit $rc, expected $code; output:"; echo "$out"; failures=$((failures + 1))
    return
  fi
  local text
  for text in "$@"; do
    if ! grep -qF -- "$text" <<<"$out"; then
      echo "FAIL $name: output lacks '$text'; output:"; echo "$out"; failures=$((failures + 1))
      return
    fi
  done
  echo "ok   $name (exit $rc)"
}

expect matching 0 allow_ok.txt \
  "2 functions over 60 lines, all on the allow-list (longest: 61 lines"
expect stale 1 allow_stale.txt \
  "fixture::(anonymous)::hidden_step is 61 lines, over the limit of 60 and not on the allow-list" \
  "fixture::long_step is now 61 lines, shorter than its allow-list entry of 64: lower the entry to 61" \
  "fixture::limit_step is listed at 62 lines but is now 60 lines, within the limit of 60: remove the entry" \
  "fixture::gone_step is listed at 70 lines but is gone: remove the entry"
expect grew 1 allow_grew.txt \
  "fixture::long_step grew to 61 lines, longer than its allow-list entry of 59"

# Without ctags: exit 2, naming the Debian package.
empty=$(mktemp -d)
out=$(PATH="$empty" "$python" "$script" --root "$fixture" --allow "$fixture/allow_ok.txt" 2>&1)
rc=$?
rmdir "$empty"
if [ "$rc" -eq 2 ] && grep -qF "universal-ctags" <<<"$out"; then
  echo "ok   no-ctags (exit 2)"
else
  echo "FAIL no-ctags: exit $rc, expected 2 naming universal-ctags; output:"; echo "$out"
  failures=$((failures + 1))
fi

if [ "$failures" -ne 0 ]; then
  echo "function_lengths_fails: $failures case(s) failed"
  exit 1
fi
echo "function_lengths_fails: the check fails on an unlisted, a grown and a stale entry"
