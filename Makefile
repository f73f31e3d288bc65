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

.PHONY: all deps configure build test demo bench install clean

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

bench: build
	@$(BUILD_DIR)/bin/slam2d_bench

# The library, headers, CMake package and tool into PREFIX (examples/consumer shows the use).
PREFIX ?= /usr/local
install: build
	@cmake --install $(BUILD_DIR) --prefix $(PREFIX)

clean:
	rm -rf $(BUILD_DIR)
