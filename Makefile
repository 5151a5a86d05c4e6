# omniloc: one entry point for everything. CMake (build/) builds the C++ and the Verilator models;
# CTest runs every test kind. `make deps` installs missing Debian packages (as root).
#
#   make            build everything (Release)
#   make test       every test: generated files, lint, formal, RTL cycle tests, host tests
#   make demo       the whole system on the simulated robot and board
#   make lint       verilator --lint-only -Wall on every RTL file
#   make formal     yosys + yosys-smtbmc (z3) proofs
#   make mutate     every mutation of tests/mutate/mutations.txt against the proofs and cycle tests
#                   ("N of N mutations killed"; MUTATE_ARGS, e.g. --formal-only, --rtl-only or --only NAME,...)
#   make bitstream  iCEBreaker bitstream with the open iCE40 flow (CHANNELS=3: a three-wheel robot's board)
#   make bench      benchmarks (each against a naive reference, ratio printed)
#   make soak       long simulated runs: the localizer (SOAK_MINUTES, default 10), the daemon with faults
#                   (SOAK_DAEMON_MINUTES, default 60 simulated; SOAK_BOARD reference or verilated)
#   make sanitize   every host test under ASan + UBSan, nothing left out, the long tests in their short
#                   mode (OMNILOC_TEST_SHORT=1; clang tree $(BUILD)/asan, scripts/sanitize.sh)
#   make fuzz       the libFuzzer harnesses of tests/fuzz, FUZZ_SECONDS each (default 60; clang tree $(BUILD)/sanitize)
#   make install    install the library, headers, programs and data under PREFIX (default /usr/local)
#   make package    the robot's Debian package omniloc_<version>_<arch>.deb (robot-only Release tree $(BUILD)/package)
#   make generate   regenerate headers and docs from common/regmap.json
#   make clean      remove build/

BUILD      ?= build
BUILD_TYPE ?= Release
JOBS       ?= $(shell nproc)
CMAKE_GEN  := $(shell command -v ninja >/dev/null 2>&1 && echo "-G Ninja")
PREFIX     ?= /usr/local
CTEST      := ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

.PHONY: all deps configure build test demo lint formal mutate bitstream bench soak sanitize fuzz install package generate clean

all: build

deps:
	@bash scripts/deps.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE)

configure: deps $(BUILD)/CMakeCache.txt

build: configure
	cmake --build $(BUILD) -j $(JOBS)

test: build
	$(CTEST)

lint: configure
	$(CTEST) -L lint

formal: configure
	$(CTEST) -L formal

# The mutations run on a copy of rtl/ (build/mutate/), never on the repository's files.
MUTATE_ARGS ?=
mutate: configure
	python3 tests/mutate/run_mutate.py --build $(BUILD) $(MUTATE_ARGS)

demo: build
	@bash scripts/demo.sh $(BUILD)

bitstream: deps
	@bash scripts/bitstream.sh $(BUILD)

bench: build
	@bash scripts/bench.sh $(BUILD)

SOAK_MINUTES ?= 10
SOAK_DAEMON_MINUTES ?= 60
SOAK_BOARD ?= reference
soak: build
	$(BUILD)/soak/soak_localizer --minutes $(SOAK_MINUTES)
	$(BUILD)/soak/soak_daemon --minutes $(SOAK_DAEMON_MINUTES) --board $(SOAK_BOARD) --out $(BUILD)/soak/daemon

# Every host test under ASan + UBSan in an optimised clang tree of its own (scripts/sanitize.sh,
# docs/TESTING.md "Every test under ASan + UBSan"); make test runs only the short ones (sanitize_gtests).
sanitize: deps
	@bash scripts/sanitize.sh . $(BUILD)/asan

# ASan + UBSan + libFuzzer in a clang tree of its own (scripts/fuzz.sh, docs/TESTING.md "Fuzzing").
FUZZ_SECONDS ?= 60
fuzz: deps
	@bash scripts/fuzz.sh run . $(BUILD)/sanitize $(FUZZ_SECONDS)

install: build
	cmake --install $(BUILD) --prefix $(PREFIX)

# CPack's DEB generator in a robot-only tree of its own (scripts/package.sh, cmake/Packaging.cmake);
# the last line printed is the .deb's path. Install it on the robot: docs/HOWTO.md, "Install on the robot".
package: deps
	@bash scripts/package.sh . $(BUILD)/package

generate:
	python3 common/gen_regmap.py

clean:
	rm -rf $(BUILD)
