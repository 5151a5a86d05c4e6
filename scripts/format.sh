#!/usr/bin/env bash
# The C++ of host/, sim/ and tests/ in the style of .clang-format (Debian 12's clang-format 14).
#   scripts/format.sh            rewrite the files in place
#   scripts/format.sh --check    list the files that differ and exit 1 (the CTest format_check)
# The two headers generated from common/regmap.json are left as the generator writes them.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
mode=write
if [ "${1:-}" = "--check" ]; then mode=check; fi
formatter=$(command -v clang-format-14 || command -v clang-format || true)
if [ -z "$formatter" ]; then
  echo "format: error: clang-format not found (Debian package clang-format; make deps installs it)" >&2
  exit 2
fi
mapfile -t files < <(find host sim tests \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \) -type f |
                     LC_ALL=C sort | xargs grep -L 'Do not edit: edit the JSON')
if [ "$mode" = write ]; then
  "$formatter" -i --style=file "${files[@]}"
  echo "format: ${#files[@]} files formatted"
  exit 0
fi
bad=()
for f in "${files[@]}"; do
  if ! "$formatter" --style=file --dry-run -Werror "$f" >/dev/null 2>&1; then bad+=("$f"); fi
done
if [ ${#bad[@]} -ne 0 ]; then
  printf 'format: %s is not formatted\n' "${bad[@]}" >&2
  echo "format: ${#bad[@]} of ${#files[@]} files differ from .clang-format: run scripts/format.sh" >&2
  exit 1
fi
echo "format: ${#files[@]} files match .clang-format"
