# Seiche: the two commands of the README's quick start, and a few for developers.
#   make run    install what is missing, build Release, bake the default scene
#   make render render one baked frame with Blender (needs Debian's blender package)
#   make test   install what is missing, build, run every test through ctest
#   make bench  every microbenchmark, then the stability suite (seiche bench --stability)
#   make check-widths  compile (only) the kernels for every SIMD width: SSE2, AVX2, AVX-512 and
#               AArch64 NEON (WIDTHS="x86-64-v4 ..." for some); what CI runs before make test
BUILD_DIR ?= build/release
JOBS ?= $(shell nproc)
SEICHE := $(BUILD_DIR)/apps/seiche
CMAKE_FLAGS ?=
WIDTHS ?=

RENDER_FRAME ?= 40

.PHONY: all deps ci-deps configure build run test bench render check-widths clean

all: build

deps:
	@bash scripts/install-deps.sh

ci-deps:
	@bash scripts/install-ci-deps.sh

configure: deps
	@cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null

# Ends by saying what was built: the SIMD width, the compiler and the flags (seiche --version).
build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)
	@$(SEICHE) --version

run: build
	$(SEICHE) bake --out out/dam_break
	@echo "make run: the baked frames (dam_break.%04d.vdb, particles.%04d.ply) and report.json are in out/dam_break/; docs/rendering.md says how to load them"

render:
	@command -v blender >/dev/null || { echo "make render: needs Blender (apt-get install blender)" >&2; exit 1; }
	@test -f out/dam_break/dam_break.$(shell printf %04d $(RENDER_FRAME)).vdb || { echo "make render: run 'make run' first (no out/dam_break/dam_break.$(shell printf %04d $(RENDER_FRAME)).vdb)" >&2; exit 1; }
	blender -b --factory-startup -P scripts/render_frame.py -- out/dam_break/dam_break.$(shell printf %04d $(RENDER_FRAME)).vdb out/dam_break/render.$(shell printf %04d $(RENDER_FRAME)).png --samples 64
	@echo "make render: out/dam_break/render.$(shell printf %04d $(RENDER_FRAME)).png"

test: build
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j $(JOBS)

# Every Google Benchmark target, medians of 5 repetitions; then the stability suite at full size.
BENCHES := bench_neighbor bench_pbf bench_kernels bench_cloth_kernels bench_cloth bench_scene_load bench_export
bench: build
	@for b in $(BENCHES); do \
	  if [ -x $(BUILD_DIR)/benchmarks/$$b ]; then \
	    $(BUILD_DIR)/benchmarks/$$b --benchmark_repetitions=5 --benchmark_report_aggregates_only=true || exit 1; fi; \
	done
	$(SEICHE) bench --stability

# Builds for widths this machine may not run, so a change that breaks one fails on any machine.
check-widths: ci-deps
	@JOBS=$(JOBS) bash scripts/check-widths.sh $(WIDTHS)

clean:
	rm -rf build out
