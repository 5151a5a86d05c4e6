#!/usr/bin/env bash
# The robot's Debian package: configures SRC into OUT as the robot-only build (OMNILOC_BUILD_SIM=OFF,
# OMNILOC_BUILD_TESTS=OFF, OMNILOC_BUILD_CALIBRATION=OFF, Release; scripts/robot_only.sh, shared with
# check_robot_only_build.sh, so CTest reuses that tree), builds omnilocd and omniloc, and runs CPack's
# DEB generator there (cmake/Packaging.cmake). Writes OUT/deb/omniloc_<version>_<arch>.deb and prints
# its path on the last line. Run by `make package` (OUT build/package) and CTest debian_package
# (scripts/check_package.sh). Usage: package.sh SRC OUT
set -euo pipefail
# shellcheck source=scripts/robot_only.sh
source "$(dirname "$0")/robot_only.sh"
src=$(realpath "$1")
out=$(realpath -m "$2")
fail() { echo "package: FAILED: $*" >&2; exit 1; }
command -v dpkg-shlibdeps >/dev/null 2>&1 || fail "dpkg-shlibdeps not found (Debian package dpkg-dev): it computes Depends"

robot_only_configure "$src" "$out"
robot_only_build "$out"
rm -rf "$out/deb"
(cd "$out" && cpack -G DEB --config "$out/CPackConfig.cmake" -B "$out/deb") >"$out.cpack.log" 2>&1 \
  || { cat "$out.cpack.log"; fail "cpack"; }
debs=("$out"/deb/omniloc_*.deb)
[ -f "${debs[0]}" ] || { cat "$out.cpack.log"; fail "cpack wrote no omniloc_*.deb into $out/deb"; }
[ "${#debs[@]}" -eq 1 ] || fail "more than one package in $out/deb: ${debs[*]}"
echo "package: $(du -h "${debs[0]}" | cut -f1) $(dpkg-deb --field "${debs[0]}" Package Version Architecture | tr '\n' ' ')"
echo "${debs[0]}"
