#!/usr/bin/env bash
# The installed omniloc is usable from outside the tree: installs the robot-only build OUT (made by
# check_robot_only_build.sh) into a fresh prefix, then
#   - runs the installed `omniloc version` and `omniloc builddb` from / (the field and camera found
#     by name under PREFIX/share/omniloc, not in a source tree),
#   - checks the systemd unit (systemd-analyze verify; ExecStart is PREFIX's omnilocd) and that the
#     udev rule was installed (its contents are checked against the EEPROM by test_firmware_eeprom),
#   - checks the installed headers: no internal header (host/src/include/) installed, each installed
#     header includes only installed ones (check_installed_headers.py --installed),
#   - builds tests/install/consumer.cpp with find_package(omniloc) (CMake) and with pkg-config
#     (--static: libomniloc.a's own dependencies are in Libs.private), runs both and compares
#     their output with the field file's numbers and a hand-computed pose.
# Run by CTest (install_consumer); usage: check_install.sh SRC OUT
set -euo pipefail
src=$(realpath "$1")
out=$(realpath -m "$2")
prefix="$out-prefix"
work="$out-consumer"
fail() { echo "install_consumer: FAILED: $*" >&2; exit 1; }

rm -rf "$prefix" "$work"
mkdir -p "$work"
cmake --install "$out" --prefix "$prefix" >"$work/install.log" 2>&1 || { cat "$work/install.log"; fail "cmake --install"; }
for f in bin/omniloc bin/omnilocd lib/libomniloc.a include/omniloc/localizer.hpp include/omniloc/regmap.hpp \
         share/omniloc/fields/fira-robosot.json share/omniloc/cameras/default.json share/omniloc/robots/default.json \
         share/omniloc/localizer/default.json share/omniloc/omnilocd/default.json \
         lib/cmake/omniloc/omnilocConfig.cmake lib/pkgconfig/omniloc.pc \
         lib/systemd/system/omnilocd.service lib/udev/rules.d/60-omniloc.rules; do
  [ -e "$prefix/$f" ] || fail "$f was not installed"
done

# The installed API: the public headers only, closed under #include.
for f in include/omniloc/detail include/omniloc/config_reader.hpp include/omniloc/calibration.hpp \
         include/omniloc/live_view.hpp include/omniloc/ros2_bridge.hpp include/omniloc/data_files.hpp; do
  [ ! -e "$prefix/$f" ] || fail "$f (internal) was installed"
done
python3 "$src/scripts/check_installed_headers.py" --installed "$prefix/include/omniloc" \
  || fail "an installed header includes one that is not installed (above)"

# The installed programs find their data relative to themselves (no OMNILOC_DATA_DIR, cwd /).
(cd / && env -u OMNILOC_DATA_DIR "$prefix/bin/omniloc" version) >"$work/version.txt" || fail "installed omniloc version"
grep -q "register map" "$work/version.txt" || { cat "$work/version.txt"; fail "omniloc version printed no register-map version"; }
(cd / && env -u OMNILOC_DATA_DIR "$prefix/bin/omniloc" builddb --out "$work/db.bin" --step 50) >"$work/builddb.txt" 2>&1 \
  || { cat "$work/builddb.txt"; fail "installed omniloc builddb did not find the installed field and camera"; }
[ -s "$work/db.bin" ] || fail "builddb wrote no database"

# The service unit names the installed daemon and passes systemd's own check (which only warns,
# exit 0, about a bad key: any output is a failure here).
unit="$prefix/lib/systemd/system/omnilocd.service"
grep -qx "ExecStart=$prefix/bin/omnilocd \$OMNILOCD_ARGS" "$unit" || fail "$unit does not start $prefix/bin/omnilocd"
grep -qx "Type=notify" "$unit" || fail "$unit is not Type=notify"
if command -v systemd-analyze >/dev/null 2>&1; then
  verify=$(cd / && systemd-analyze verify "$unit" 2>&1) || { echo "$verify"; fail "systemd-analyze verify $unit"; }
  [ -z "$verify" ] || { echo "$verify"; fail "systemd-analyze verify complained about $unit"; }
else
  echo "install_consumer: systemd-analyze not installed: the unit's syntax was not checked"
fi

expected=$'field fira-robosot 600 x 400 cm\ncompose 100.0 60.0 90.0'
gen=()
command -v ninja >/dev/null 2>&1 && gen=(-G Ninja)
cmake -S "$src/tests/install" -B "$work/cmake" "${gen[@]}" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
  >"$work/cmake.log" 2>&1 || { cat "$work/cmake.log"; fail "find_package(omniloc) consumer: configure"; }
cmake --build "$work/cmake" >"$work/cmake-build.log" 2>&1 || { cat "$work/cmake-build.log"; fail "find_package(omniloc) consumer: build"; }
got=$(OMNILOC_DATA_DIR="$prefix/share/omniloc" "$work/cmake/consumer") || fail "find_package consumer did not run"
[ "$got" = "$expected" ] || fail "find_package consumer printed '$got', expected '$expected'"

export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"
# libusb and libsystemd are the library's own (Libs.private): not in the plain link line.
plain_libs=$(pkg-config --libs omniloc) || fail "pkg-config --libs omniloc"
case "$plain_libs" in *usb*|*systemd*) fail "pkg-config --libs omniloc names a private dependency: $plain_libs" ;; esac
# shellcheck disable=SC2046  # pkg-config prints several words
c++ -O1 -o "$work/consumer-pc" "$src/tests/install/consumer.cpp" $(pkg-config --static --cflags --libs omniloc) \
  >"$work/pc-build.log" 2>&1 || { cat "$work/pc-build.log"; fail "pkg-config consumer: build"; }
got=$(OMNILOC_DATA_DIR="$prefix/share/omniloc" "$work/consumer-pc") || fail "pkg-config consumer did not run"
[ "$got" = "$expected" ] || fail "pkg-config consumer printed '$got', expected '$expected'"
echo "install_consumer: installed into $prefix; omniloc and omnilocd run from /, find_package and pkg-config consumers built and ran"
