#!/usr/bin/env bash
# The C++ of host/, sim/ and tests/ in the style of .clang-format (Debian 12's clang-format 14).
#   scripts/format.sh            rewrite the files in place
#   scripts/format.sh --check    list the files that differ and exit 1 (the CTest format_check)
# The two headers generated from common/regmap.json are left as the generator writes them.
# The RTL's layout is checked, not rewritten (no Verilog formatter in Debian 12): as in Forencich's
# cores, module items start at column 0 inside module ... endmodule, nesting is 4 spaces, no tabs
# and no trailing spaces.
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
rtl_bad=$(awk 'FNR == 1 { in_module = 0 }
  /^\) *;/ { in_module = 1; next }
  /^endmodule/ { in_module = 0 }
  in_module && /^    (wire|reg|always|assign|localparam|parameter|function|generate|initial|genvar|integer)[ @(]/ {
    print FILENAME ":" FNR ": a module item is indented (module items start at column 0)" }
  /\t/ { print FILENAME ":" FNR ": a tab (indent with 4 spaces)" }
  / +$/ { print FILENAME ":" FNR ": trailing spaces" }' $(find rtl -name '*.v' -o -name '*.vh' | LC_ALL=C sort))
if [ -n "$rtl_bad" ]; then
  echo "$rtl_bad" >&2
  echo "format: the RTL's layout differs from its style (scripts/format.sh, top)" >&2
  exit 1
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
echo "format: ${#files[@]} C++ files match .clang-format, the RTL its layout rules"
