#!/usr/bin/env bash
# The robot's library and programs build without the simulator, the tests and the calibration:
# configures SRC with -DOMNILOC_BUILD_SIM=OFF -DOMNILOC_BUILD_TESTS=OFF -DOMNILOC_BUILD_CALIBRATION=OFF
# into OUT, builds omnilocd and omniloc, and checks that nothing of the simulator got in: no
# Verilator or Ceres in the configuration, no omniloc::sim or
# Verilated symbol in omnilocd, no host/ source that includes a simulator header. Prints omnilocd's
# dynamic libraries (ldd). Run by CTest (robot_only_build); usage: check_robot_only_build.sh SRC OUT
set -euo pipefail
# shellcheck source=scripts/robot_only.sh
source "$(dirname "$0")/robot_only.sh"
src=$(realpath "$1")
out=$(realpath -m "$2")

fail() { echo "robot_only_build: FAILED: $*" >&2; exit 1; }

if grep -rn --include='*.hpp' --include='*.cpp' -E '#include [<"](omniloc_sim/|V[a-z_]+\.h|verilated)' "$src/host"; then
  fail "host/ includes a simulator or Verilator header (above)"
fi

robot_only_configure "$src" "$out"
if grep -q "^verilator_DIR" "$out/CMakeCache.txt"; then fail "the robot-only configuration looked for Verilator"; fi
if grep -q "^Ceres_DIR" "$out/CMakeCache.txt"; then fail "the robot-only configuration looked for Ceres"; fi
robot_only_build "$out"
for t in omniloc_sim omniloc_board_sim omniloc_sim_daemon vencoder_core; do
  if grep -q "^build [^:]*$t" "$out/build.ninja" 2>/dev/null; then fail "target $t exists in the robot-only build"; fi
done
bin="$out/bin/omnilocd"
[ -x "$bin" ] || fail "$bin was not built"
if nm -C "$bin" | grep -E 'omniloc::sim::|Verilated|Vomniloc' | head -5 | grep -q .; then
  nm -C "$bin" | grep -E 'omniloc::sim::|Verilated|Vomniloc' | head -5
  fail "omnilocd contains simulator symbols (above)"
fi
if ldd "$bin" | grep -q "libceres"; then fail "omnilocd links Ceres"; fi
echo "robot_only_build: omnilocd links (ldd):"
ldd "$bin" | awk '{print "  " $1}' | sort
"$bin" --help >/dev/null || fail "omnilocd --help"
"$out/bin/omniloc" --help >/dev/null || fail "omniloc --help"
echo "robot_only_build: OK: omnilocd and omniloc built with OMNILOC_BUILD_SIM=OFF OMNILOC_BUILD_TESTS=OFF, no simulator in them"
