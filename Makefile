# SPDX-License-Identifier: BSD-3-Clause
# slam2d: the two set-up commands (see README.md) and a few conveniences.
#   make demo   install dependencies, build, run the demo on the simulated office world
#   make test   install dependencies, build, run every test

BUILD_DIR ?= build/release
JOBS ?= 2
CMAKE_FLAGS ?=
DEMO_OUT ?= out/demo
# Real-data tests read $SLAM2D_DATA; default to the shared data folder beside the repo.
SLAM2D_DATA ?= $(abspath $(wildcard ../shared/data))
export SLAM2D_DATA

.PHONY: all deps configure build test demo bench install clean fuzz-build fuzz fuzz-smoke check-sanitizers check-tsan

all: build

deps:
	@bash scripts/install-deps.sh

configure: deps
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null

build: configure
	@cmake --build $(BUILD_DIR) -j$(JOBS)

test: build
	@cd $(BUILD_DIR) && ctest --output-on-failure -j$(JOBS)

# The demo needs the tool alone, not the tests and benchmarks.
demo: configure
	@cmake --build $(BUILD_DIR) -j$(JOBS) --target slam2d
	@$(BUILD_DIR)/bin/slam2d demo --out $(DEMO_OUT)

# Reliability (docs/reliability.md). The fuzz targets: a clang build with libFuzzer, ASan and UBSan
# of the parsers; `make fuzz` runs each for FUZZ_SECONDS over corpora seeded from the real data,
# `make fuzz-smoke` (CI) for 10 s each. (Without CMAKE_FLAGS: -Werror is for the GCC build.)
FUZZ_DIR ?= build/fuzz
FUZZ_SECONDS ?= 600
fuzz-build: deps
	@CXX=clang++ cmake -S . -B $(FUZZ_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSLAM2D_FUZZ=ON -DSLAM2D_BUILD_TESTS=OFF \
	  -DSLAM2D_BUILD_BENCH=OFF -DSLAM2D_BUILD_PYTHON=OFF -DSLAM2D_BUILD_CLI=OFF -DSLAM2D_INSTALL=OFF >/dev/null
	@cmake --build $(FUZZ_DIR) -j$(JOBS) --target fuzz_all

# The seed corpora use the release build's CLI (simulated logs and bags).
fuzz: build fuzz-build
	@SLAM2D_BIN=$(abspath $(BUILD_DIR))/bin/slam2d bash fuzz/run.sh $(FUZZ_DIR) $(FUZZ_SECONDS)

fuzz-smoke:
	@$(MAKE) --no-print-directory fuzz FUZZ_SECONDS=10

# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer, and the multi-threaded
# code (the RBPF's particles, the ROS 1 bag reader's decompression) under ThreadSanitizer.
SANITIZE_FLAGS = -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSLAM2D_BUILD_BENCH=OFF -DSLAM2D_BUILD_PYTHON=OFF $(CMAKE_FLAGS)
check-sanitizers: deps
	@cmake -S . -B build/asan -DSLAM2D_SANITIZE=address,undefined $(SANITIZE_FLAGS) >/dev/null
	@cmake --build build/asan -j$(JOBS)
	@cd build/asan && ctest --output-on-failure -j$(JOBS)
	@$(MAKE) --no-print-directory check-tsan

# ThreadSanitizer alone (CI runs it): the RBPF's parallel tests and the ROS 1 bag reader's, real
# data included when SLAM2D_DATA is set. Any report fails the run.
check-tsan: deps
	@cmake -S . -B build/tsan -DSLAM2D_SANITIZE=thread $(SANITIZE_FLAGS) >/dev/null
	@cmake --build build/tsan -j$(JOBS) --target slam2d_test_threads
	@TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" build/tsan/tests/slam2d_test_threads

bench: build
	@$(BUILD_DIR)/bin/slam2d_bench

# The library, headers, CMake package and tool into PREFIX (examples/consumer shows the use).
PREFIX ?= /usr/local
install: build
	@cmake --install $(BUILD_DIR) --prefix $(PREFIX)

clean:
	rm -rf $(BUILD_DIR)
