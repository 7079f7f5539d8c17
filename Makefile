# Seiche: the two commands of the README's quick start, and a few for developers.
#   make run    install what is missing, build Release, bake the default scene
#   make test   install what is missing, build, run every test through ctest
BUILD_DIR ?= build/release
JOBS ?= $(shell nproc)
SEICHE := $(BUILD_DIR)/apps/seiche
CMAKE_FLAGS ?=

.PHONY: all deps configure build run test bench clean

all: build

deps:
	@bash scripts/install-deps.sh

configure: deps
	@cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null

build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

run: build
	$(SEICHE) run --out out/dam_break --report out/dam_break/report.json
	@echo "make run: particle frames and report.json are in out/dam_break/"

test: build
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j $(JOBS)

bench: build
	$(BUILD_DIR)/benchmarks/bench_neighbor --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
	$(BUILD_DIR)/benchmarks/bench_pbf --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

clean:
	rm -rf build out
