#!/usr/bin/env bash
# The robot's Debian package: configures SRC into OUT as the robot-only build (OMNILOC_BUILD_SIM=OFF,
# OMNILOC_BUILD_TESTS=OFF, OMNILOC_BUILD_CALIBRATION=OFF, Release; the same configuration as
# check_robot_only_build.sh, so CTest reuses that tree), builds omnilocd and omniloc, and runs CPack's
# DEB generator there (cmake/Packaging.cmake). Writes OUT/deb/omniloc_<version>_<arch>.deb and prints
# its path on the last line. Run by `make package` (OUT build/package) and CTest debian_package
# (scripts/check_package.sh). Usage: package.sh SRC OUT
set -euo pipefail
src=$(realpath "$1")
out=$(realpath -m "$2")
gen=()
command -v ninja >/dev/null 2>&1 && gen=(-G Ninja)
fail() { echo "package: FAILED: $*" >&2; exit 1; }
command -v dpkg-shlibdeps >/dev/null 2>&1 || fail "dpkg-shlibdeps not found (Debian package dpkg-dev): it computes Depends"

mkdir -p "$out"
cmake -S "$src" -B "$out" "${gen[@]}" -DCMAKE_BUILD_TYPE=Release -DOMNILOC_BUILD_SIM=OFF -DOMNILOC_BUILD_TESTS=OFF \
  -DOMNILOC_BUILD_CALIBRATION=OFF >"$out.configure.log" 2>&1 || { cat "$out.configure.log"; fail "configure"; }
cmake --build "$out" --target omnilocd omniloc_cli -j "$(nproc)" >"$out.build.log" 2>&1 \
  || { tail -50 "$out.build.log"; fail "build"; }
rm -rf "$out/deb"
(cd "$out" && cpack -G DEB --config "$out/CPackConfig.cmake" -B "$out/deb") >"$out.cpack.log" 2>&1 \
  || { cat "$out.cpack.log"; fail "cpack"; }
debs=("$out"/deb/omniloc_*.deb)
[ -f "${debs[0]}" ] || { cat "$out.cpack.log"; fail "cpack wrote no omniloc_*.deb into $out/deb"; }
[ "${#debs[@]}" -eq 1 ] || fail "more than one package in $out/deb: ${debs[*]}"
echo "package: $(du -h "${debs[0]}" | cut -f1) $(dpkg-deb --field "${debs[0]}" Package Version Architecture | tr '\n' ' ')"
echo "${debs[0]}"
