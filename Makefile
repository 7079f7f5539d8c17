# Seiche: the two commands of the README's quick start, and a few for developers.
#   make run    install what is missing, build Release, bake the default scene
#   make render render one baked frame with Blender (needs Debian's blender package)
#   make blender-addon  the Blender add-on (blender/addons/seiche_importer) as build/seiche_importer.zip
#   make test   install what is missing (and Blender, for the add-on's test), build, run every test through ctest
#   make bench  every microbenchmark, then the stability suite (seiche bench --stability)
#   make check-widths  compile (only) the kernels for every SIMD width: SSE2, AVX2, AVX-512 and
#               AArch64 NEON (WIDTHS="x86-64-v4 ..." for some); what CI runs before make test
#   make asan   build with AddressSanitizer and UBSan (g++, -O1, build/asan) and run the tests
#               labelled "fast" (tests/CMakeLists.txt); what CI runs after make test
#   make install  install the library, headers, CMake package, CLI and Python package into PREFIX
#               (default /usr/local; docs/api.md)
#   make fuzz   build the libFuzzer targets (clang-14, sanitizers, build/fuzz) and run each for
#               FUZZ_SECONDS seconds (default 60): the scene loader and the checkpoint reader
BUILD_DIR ?= build/release
JOBS ?= $(shell nproc)
SEICHE := $(BUILD_DIR)/apps/seiche
CMAKE_FLAGS ?=
WIDTHS ?=
ASAN_DIR ?= build/asan
FUZZ_DIR ?= build/fuzz
FUZZ_SECONDS ?= 60

RENDER_FRAME ?= 40
PREFIX ?= /usr/local

.PHONY: all deps ci-deps configure build run test bench render blender-addon install check-widths asan fuzz clean

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
	@command -v blender >/dev/null || { echo "make render: needs Blender (apt-get install blender python3-numpy)" >&2; exit 1; }
	@test -f out/dam_break/bake.json || { echo "make render: run 'make run' first (no bake in out/dam_break)" >&2; exit 1; }
	blender -b --factory-startup -P scripts/render_frame.py -- out/dam_break $(RENDER_FRAME) out/dam_break/render.$(shell printf %04d $(RENDER_FRAME)).png --samples 64
	@echo "make render: out/dam_break/render.$(shell printf %04d $(RENDER_FRAME)).png"

# The Blender add-on as the zip Blender's preferences install (Add-ons > Install...).
blender-addon:
	@mkdir -p build
	@cd blender/addons && python3 -c 'import os, sys, zipfile; z = zipfile.ZipFile(sys.argv[1], "w", zipfile.ZIP_DEFLATED); \
	  [z.write(os.path.join(d, f)) for d, _, fs in os.walk("seiche_importer") for f in sorted(fs) if f.endswith(".py")]' ../../build/seiche_importer.zip
	@echo "make blender-addon: build/seiche_importer.zip (Blender: Edit > Preferences > Add-ons > Install..., then tick 'Import-Export: Seiche bake')"

# Test-only packages, installed by `make test` when missing (not by `make run`): Debian's Blender,
# for the add-on's test (tests/blender/). The add-on reads frames with NumPy: Debian's blender uses
# the system python3-numpy, which scripts/install-deps.sh installs for the Python module's tests.
TEST_DEPS := blender

test: build
	@bash scripts/install-deps.sh $(TEST_DEPS)
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j $(JOBS)

install: build
	cmake --install $(BUILD_DIR) --prefix $(PREFIX)

# Every Google Benchmark target, medians of 5 repetitions; then the stability suite at full size.
BENCHES := bench_neighbor bench_pbf bench_kernels bench_cloth_kernels bench_cloth bench_bodies bench_scene_load bench_export
bench: build
	@for b in $(BENCHES); do \
	  if [ -x $(BUILD_DIR)/benchmarks/$$b ]; then \
	    $(BUILD_DIR)/benchmarks/$$b --benchmark_repetitions=5 --benchmark_report_aggregates_only=true || exit 1; fi; \
	done
	$(SEICHE) bench --stability

# Builds for widths this machine may not run, so a change that breaks one fails on any machine.
check-widths: ci-deps
	@JOBS=$(JOBS) bash scripts/check-widths.sh $(WIDTHS)

# -O1 keeps the sanitized tests fast enough; NDEBUG as in Release, so the same code is checked.
# No Python module: a sanitized shared object cannot load into an unsanitized python3.
# A UBSan report fails its test (-fno-sanitize-recover); so does an ASan one, or a leak.
SANITIZE_FLAGS := -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer
asan: deps
	@cmake -S . -B $(ASAN_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" "-DCMAKE_CXX_FLAGS=$(SANITIZE_FLAGS)" \
	  -DSEICHE_BUILD_BENCHMARKS=OFF -DSEICHE_BUILD_PYTHON=OFF $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(ASAN_DIR) -j $(JOBS)
	UBSAN_OPTIONS=print_stacktrace=1 ctest --test-dir $(ASAN_DIR) -L fast --output-on-failure -j $(JOBS)

# clang-14 and its sanitizer runtimes (libclang-rt-14-dev) are installed here when missing: only
# the fuzz build needs them. OpenVDB, the tests, the benchmarks and the Python module are left out of it.
fuzz:
	@bash scripts/install-deps.sh clang-14 libclang-rt-14-dev
	@cmake -S . -B $(FUZZ_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -DNDEBUG" -DCMAKE_CXX_COMPILER=clang++-14 -DSEICHE_FUZZ=ON \
	  -DSEICHE_WITH_OPENVDB=OFF -DSEICHE_BUILD_TESTS=OFF -DSEICHE_BUILD_BENCHMARKS=OFF -DSEICHE_BUILD_PYTHON=OFF >/dev/null
	@cmake --build $(FUZZ_DIR) -j $(JOBS) --target fuzz_scene_loader fuzz_checkpoint_reader write_checkpoint_seeds
	@FUZZ_SECONDS=$(FUZZ_SECONDS) bash fuzz/run_fuzzers.sh $(FUZZ_DIR)

clean:
	rm -rf build out
