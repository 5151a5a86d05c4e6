# The robot-only build, in one place (sourced by scripts/check_robot_only_build.sh and
# scripts/package.sh, so CTest's robot_only_build and debian_package share one tree): the library and
# the programs, without the simulator, the tests and the calibration, Release. Needs `fail`.
#
#   robot_only_configure SRC OUT    configure SRC into OUT (log OUT.configure.log)
#   robot_only_build OUT            build omnilocd and omniloc there (log OUT.build.log)
robot_only_configure() {
  local src=$1 out=$2 gen=()
  command -v ninja >/dev/null 2>&1 && gen=(-G Ninja)
  mkdir -p "$out"
  cmake -S "$src" -B "$out" "${gen[@]}" -DCMAKE_BUILD_TYPE=Release -DOMNILOC_BUILD_SIM=OFF \
    -DOMNILOC_BUILD_TESTS=OFF -DOMNILOC_BUILD_CALIBRATION=OFF >"$out.configure.log" 2>&1 \
    || { cat "$out.configure.log"; fail "configure"; }
}

robot_only_build() {
  local out=$1
  cmake --build "$out" --target omnilocd omniloc_cli -j "$(nproc)" >"$out.build.log" 2>&1 \
    || { tail -50 "$out.build.log"; fail "build"; }
}
