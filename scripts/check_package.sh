#!/usr/bin/env bash
# The robot's Debian package is complete and installable: builds it with scripts/package.sh in OUT
# (the robot-only tree of check_robot_only_build.sh, reused), then
#   - its metadata (dpkg-deb --field): Package omniloc, Version = project(VERSION) of CMakeLists.txt,
#     Architecture = dpkg --print-architecture, the file named omniloc_<version>_<arch>.deb,
#     Maintainer, Description and Homepage set, Depends not empty and naming only real Debian
#     packages (each known to dpkg or apt), among them the package of every library that omniloc and
#     omnilocd link directly (readelf NEEDED -> ldd -> dpkg -S);
#   - its contents (dpkg-deb --contents): the programs, the library, headers, CMake package,
#     pkg-config file, every data file of common/{fields,cameras,robots,localizer,omnilocd}, the
#     systemd unit and the udev rule, under /usr; no build or staging path inside any text file;
#   - its maintainer scripts (postinst, prerm, postrm: executable, sh -n, and each exits 0 when run
#     with systemctl and udevadm stubbed, so that nothing on this machine changes);
#   - unpacked (dpkg-deb -x) into a temporary folder: the unit starts /usr/bin/omnilocd, and the
#     unpacked `usr/bin/omniloc --version` and `omnilocd --version` print the project version and
#     `omniloc builddb` finds the unpacked data (relative to the program, from /, no OMNILOC_DATA_DIR);
#   - that the check can fail: the same package rebuilt without the udev rule is refused, naming it.
# Run by CTest (debian_package); usage: check_package.sh SRC OUT
set -euo pipefail
src=$(realpath "$1")
out=$(realpath -m "$2")
work="$out-package-check"
fail() { echo "debian_package: FAILED: $*" >&2; exit 1; }

rm -rf "$work"
mkdir -p "$work"
bash "$src/scripts/package.sh" "$src" "$out" >"$work/package.txt" 2>&1 || { cat "$work/package.txt"; fail "scripts/package.sh"; }
deb=$(tail -n 1 "$work/package.txt")
[ -f "$deb" ] || { cat "$work/package.txt"; fail "scripts/package.sh printed no package path"; }

version=$(sed -n 's/^project(omniloc VERSION \([0-9.]*\) .*/\1/p' "$src/CMakeLists.txt")
[ -n "$version" ] || fail "no project(omniloc VERSION ...) in $src/CMakeLists.txt"
arch=$(dpkg --print-architecture)

# The package's metadata, contents and maintainer scripts; fails naming the first thing wrong.
check_deb() {
  local deb=$1 scratch=$2 f field pkg
  [ "$(basename "$deb")" = "omniloc_${version}_${arch}.deb" ] || fail "$(basename "$deb") is not named omniloc_${version}_${arch}.deb"
  dpkg-deb --info "$deb" >"$scratch/info.txt" || fail "dpkg-deb --info $deb"
  [ "$(dpkg-deb --field "$deb" Package)" = omniloc ] || fail "Package is '$(dpkg-deb --field "$deb" Package)', not omniloc"
  [ "$(dpkg-deb --field "$deb" Version)" = "$version" ] || fail "Version is '$(dpkg-deb --field "$deb" Version)', not $version"
  [ "$(dpkg-deb --field "$deb" Architecture)" = "$arch" ] || fail "Architecture is '$(dpkg-deb --field "$deb" Architecture)', not $arch"
  for field in Maintainer Description Homepage Depends; do
    [ -n "$(dpkg-deb --field "$deb" "$field")" ] || fail "the package has no $field"
  done
  # Depends: "a (>= 1), b | c, ..." -> one name a line; each a package dpkg or apt knows.
  dpkg-deb --field "$deb" Depends | tr ',|' '\n' | sed 's/(.*)//; s/:any//; s/[[:space:]]//g' | sed '/^$/d' \
    | sort -u >"$scratch/depends.txt"
  while read -r pkg; do
    dpkg-query -W "$pkg" >/dev/null 2>&1 || apt-cache show "$pkg" >/dev/null 2>&1 \
      || fail "Depends names $pkg, which is no Debian package known to dpkg or apt"
  done <"$scratch/depends.txt"

  dpkg-deb --contents "$deb" | awk '{print $NF}' | sed 's|^\./||' >"$scratch/contents.txt" || fail "dpkg-deb --contents $deb"
  local expected=(usr/bin/omniloc usr/bin/omnilocd usr/lib/libomniloc.a
    usr/include/omniloc/localizer.hpp usr/include/omniloc/regmap.hpp
    usr/lib/cmake/omniloc/omnilocConfig.cmake usr/lib/cmake/omniloc/omnilocConfigVersion.cmake
    usr/lib/pkgconfig/omniloc.pc
    usr/lib/systemd/system/omnilocd.service usr/lib/udev/rules.d/60-omniloc.rules)
  for f in $(cd "$src/common" && find fields cameras robots localizer omnilocd -type f | sort); do
    expected+=("usr/share/omniloc/$f")
  done
  for f in "${expected[@]}"; do
    grep -qx "$f" "$scratch/contents.txt" || fail "$f is not in $(basename "$deb")"
  done
  if grep -v '^usr/' "$scratch/contents.txt" | grep -v '^$' | grep -q .; then
    grep -v '^usr/' "$scratch/contents.txt" | grep -v '^$' | head -5
    fail "files outside /usr in $(basename "$deb") (above)"
  fi

  mkdir -p "$scratch/control"
  dpkg-deb --control "$deb" "$scratch/control" || fail "dpkg-deb --control $deb"
  for f in postinst prerm postrm; do
    [ -x "$scratch/control/$f" ] || fail "the maintainer script $f is not in $(basename "$deb") (or not executable)"
    sh -n "$scratch/control/$f" || fail "the maintainer script $f is not valid sh"
  done
}

check_deb "$deb" "$work"
# The maintainer scripts exit 0 with and without systemd and udev running; systemctl and udevadm
# are stubs here (they log their calls), so that the check changes nothing on the machine it runs on.
mkdir -p "$work/stubs"
for stub in systemctl udevadm; do
  printf '#!/bin/sh\necho "%s $*" >>"%s/stub-calls.txt"\n' "$stub" "$work" >"$work/stubs/$stub"
  chmod +x "$work/stubs/$stub"
done
for step in postinst:configure prerm:remove postrm:remove postrm:purge; do
  script=${step%%:*} action=${step#*:}
  PATH="$work/stubs:$PATH" sh "$work/control/$script" "$action" >"$work/$script-$action.txt" 2>&1 \
    || { cat "$work/$script-$action.txt"; fail "the maintainer script '$script $action' failed"; }
done
echo "debian_package: $(basename "$deb"): Depends: $(dpkg-deb --field "$deb" Depends)"

# Unpacked: the programs run, say the project version and find their data relative to themselves.
root="$work/root"
dpkg-deb -x "$deb" "$root" || fail "dpkg-deb -x $deb"
unit="$root/usr/lib/systemd/system/omnilocd.service"
grep -qx "ExecStart=/usr/bin/omnilocd \$OMNILOCD_ARGS" "$unit" || { grep ExecStart "$unit"; fail "$unit does not start /usr/bin/omnilocd"; }
if grep -rlI -e "$out" -e _CPack_Packages "$root" | head -5 | grep .; then
  fail "build or staging paths in the unpacked files (above)"
fi
for prog in omniloc omnilocd; do
  got=$(cd / && env -u OMNILOC_DATA_DIR "$root/usr/bin/$prog" --version) || fail "the unpacked usr/bin/$prog --version failed"
  case "$got" in
    "$prog $version "*) ;;
    *) fail "the unpacked usr/bin/$prog --version printed '$got', expected '$prog $version ...'" ;;
  esac
done
(cd / && env -u OMNILOC_DATA_DIR "$root/usr/bin/omniloc" builddb --out "$work/db.bin" --step 50) >"$work/builddb.txt" 2>&1 \
  || { cat "$work/builddb.txt"; fail "the unpacked omniloc builddb did not find the unpacked field and camera"; }
[ -s "$work/db.bin" ] || fail "the unpacked omniloc builddb wrote no database"

# Every library the programs link directly comes from a package named in Depends.
for prog in omniloc omnilocd; do
  for lib in $(readelf -d "$root/usr/bin/$prog" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
    path=$(ldd "$root/usr/bin/$prog" | awk -v l="$lib" '$1 == l {print $3}')
    [ -n "$path" ] || fail "usr/bin/$prog needs $lib, which ldd does not find"
    owner=$(dpkg -S "$(realpath "$path")" 2>/dev/null || dpkg -S "$path" 2>/dev/null) \
      || fail "usr/bin/$prog needs $lib ($path), which no Debian package holds"
    owner=${owner%%:*}
    grep -qx "$owner" "$work/depends.txt" || fail "usr/bin/$prog needs $lib from $owner, which Depends does not name"
  done
done

# The check can fail: the same package without the udev rule is refused, naming the rule.
bad="$work/bad"
mkdir -p "$bad/tree" "$bad/deb" "$bad/scratch"
dpkg-deb -R "$deb" "$bad/tree"
rm "$bad/tree/usr/lib/udev/rules.d/60-omniloc.rules"
dpkg-deb --root-owner-group -b "$bad/tree" "$bad/deb/$(basename "$deb")" >/dev/null 2>&1 || fail "dpkg-deb -b of the damaged copy"
if (check_deb "$bad/deb/$(basename "$deb")" "$bad/scratch") 2>"$bad/err.txt"; then
  fail "a package without usr/lib/udev/rules.d/60-omniloc.rules passed the check"
fi
grep -q "usr/lib/udev/rules.d/60-omniloc.rules is not in" "$bad/err.txt" || { cat "$bad/err.txt"; fail "the damaged package was refused for another reason"; }

echo "debian_package: OK: $deb ($(du -h "$deb" | cut -f1)): $(wc -l <"$work/contents.txt") entries, the programs unpacked say $version and find their data; a package without the udev rule is refused"
