#!/usr/bin/env bash
# Installs the Debian 12 packages omniloc needs, and only those that are missing.
# Called by `make deps`, a prerequisite of `make`, `make test` and `make demo`.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config python3 dpkg-dev file
  verilator yosys nextpnr-ice40 fpga-icestorm z3
  libeigen3-dev libopencv-dev libusb-1.0-0-dev libsystemd-dev libceres-dev nlohmann-json3-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  umockdev libumockdev-dev libglib2.0-dev
  ftdi-eeprom
  cyclonedds-dev cyclonedds-tools
  libcpp-httplib-dev chromium
  clang libclang-rt-14-dev clang-format universal-ctags
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "deps: all ${#packages[@]} Debian packages present"
  exit 0
fi

echo "deps: missing Debian packages: ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "deps: error: installing them needs root. Run as root, or:" >&2
  echo "  sudo apt-get update && sudo apt-get install -y ${missing[*]}" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update
apt-get install -y --no-install-recommends "${missing[@]}"
echo "deps: installed ${#missing[@]} package(s)"
