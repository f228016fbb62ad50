# keymesh: the two commands are `make demo` and `make test`.
# Everything else (deps, build, bench) is a step of those two or a helper.

BUILD_DIR ?= build
JOBS ?= $(shell nproc)
PYTHON ?= /usr/bin/python3
CMAKE_FLAGS ?=
ifeq ($(CI),true)
CMAKE_FLAGS += -DKEYMESH_WERROR=ON
endif

# Debian 12 packages the build, the tests and the demo need.
DEBIAN_PACKAGES = build-essential cmake ninja-build pkg-config \
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev zlib1g-dev \
  python3 python3-numpy python3-vtk9 libvolpack1-dev mricron-data \
  pybind11-dev libdlpack-dev python3-dev python3-pytest python3-skimage python3-meshio \
  clang-14 libfuzzer-14-dev libclang-rt-14-dev libopenmpi-dev openmpi-bin \
  libgdcm-dev libblosc-dev libdeflate-dev libgmp-dev libtinygltf-dev python3-pydicom python3-zarr \
  python3-open3d python3-dask python3-distributed libdraco-dev draco
# and those `make bench` adds for its peers, plots and pictures.
BENCH_PACKAGES = libthrust-dev libtbb-dev libvtk9-dev python3-openvdb python3-matplotlib xvfb hyperfine

.PHONY: all deps build gpu-check-build demo test bench scaling cli-docs clean sanitize sanitize-quick fuzz fuzz-build fuzz-run gltf-validator

all: build

# Installs the missing Debian packages when run as root, otherwise says which
# ones to install.
deps:
	@missing=""; for p in $(DEBIAN_PACKAGES) $(EXTRA_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    echo "make deps: installing$$missing"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing >/dev/null || exit 1; \
	  else \
	    echo "make deps: missing Debian packages:$$missing"; \
	    echo "  run: sudo apt-get install$$missing"; exit 1; \
	  fi; \
	fi

build: deps
	@cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(BUILD_DIR) -j $(JOBS)

# The GPU check's self-contained programs (docs/gpu-check.md): the command,
# the CUDA tests and the timing program in build-gpucheck/, needing only libc,
# libm and the driver's libcuda; scripts/gpu_check.sh runs them on a GPU machine.
GPU_CHECK_DIR = build-gpucheck
GPU_CHECK_PROGRAMS = keymesh keymesh_cuda_tests keymesh_gpu_timing
gpu-check-build:
	@cmake -S . -B $(GPU_CHECK_DIR) -G Ninja -C cmake/gpu_check.cmake $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(GPU_CHECK_DIR) -j $(JOBS) --target $(GPU_CHECK_PROGRAMS)
	@cd $(GPU_CHECK_DIR) && strip $(GPU_CHECK_PROGRAMS) && $(PYTHON) ../scripts/gpu_check_linkage.py $(GPU_CHECK_PROGRAMS)

demo: build
	@$(PYTHON) scripts/demo.py --keymesh $(BUILD_DIR)/keymesh --out out

# The Khronos glTF validator (npm package gltf-validator, pinned) that
# tests/cli/test_gltf_validator_cli.py runs over the .glb files keymesh
# writes: installed under $(BUILD_DIR)/node when missing. Without npm the
# test is skipped, except under CI=true, where this step fails.
GLTF_VALIDATOR_VERSION = 2.0.0-dev.3.10
gltf-validator:
	@if [ ! -f $(BUILD_DIR)/node/node_modules/gltf-validator/package.json ]; then \
	  if command -v npm >/dev/null && command -v node >/dev/null; then \
	    echo "make gltf-validator: npm install gltf-validator@$(GLTF_VALIDATOR_VERSION) into $(BUILD_DIR)/node"; \
	    mkdir -p $(BUILD_DIR)/node && npm install --prefix $(BUILD_DIR)/node --no-audit --no-fund --silent \
	      gltf-validator@$(GLTF_VALIDATOR_VERSION) || exit 1; \
	  elif [ "$(CI)" = true ]; then echo "make gltf-validator: node and npm are needed under CI=true"; exit 1; \
	  else echo "make gltf-validator: no node/npm: the .glb validator test will be skipped"; fi; \
	fi

# Every test, then a short sanitized run (SANITIZE_QUICK=0 skips it).
SANITIZE_QUICK ?= 1
test: build gltf-validator
	@cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)
ifneq ($(SANITIZE_QUICK),0)
	@$(MAKE) --no-print-directory sanitize-quick
endif

# The distributed contour for 1..8 MPI ranks -> docs/SCALING.md.
scaling: build
	@$(PYTHON) bench/scaling.py --build $(BUILD_DIR)

# docs/cli/<command>.md: each command's --help, rewritten from the built binary
# (tests/cli/test_cli_docs.py fails when a page differs).
cli-docs: build
	@$(PYTHON) scripts/cli_docs.py --keymesh $(BUILD_DIR)/keymesh

bench: EXTRA_PACKAGES = $(BENCH_PACKAGES)
bench: build
	@$(PYTHON) bench/run.py --build $(BUILD_DIR) $(if $(QUICK),--quick,)

# Sanitizers (issue 11): the whole ctest suite under AddressSanitizer +
# UndefinedBehaviorSanitizer (build-asan), then the threaded primitives and
# generators under ThreadSanitizer (build-tsan; clang with LLVM's OpenMP,
# whose Archer tool tells TSan about OpenMP's synchronisation).
SANITIZE_CMAKE = -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DKEYMESH_PYTHON=OFF -DKEYMESH_BUILD_BENCH=OFF -DKEYMESH_CUDA=OFF
TSAN_FILTER ?= *Threads*:ExclusiveScan*:BitsNeeded*:Contour*:ContourTets*:Tetrahedralize*:Subdivide*:Coarsen*:Dual*:Curvature*:Incidence*:TopologyTest*
SANITIZER_ENV = KEYMESH_HUGE_PAGES=0 ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1 \
  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan_suppressions.txt:print_suppressions=0 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1:ignore_noninstrumented_modules=1 \
  OMP_TOOL_LIBRARIES=/usr/lib/llvm-14/lib/libarcher.so

# The short sanitized run of `make test`: one clang build (build-fuzz,
# ASan + UBSan + libFuzzer's coverage instrumentation, -O1, and
# -DKEYMESH_POISON_UNWRITTEN: elements of core/array.hpp's Array that nobody
# wrote hold all-ones bits, so a read of one shows in the outputs) gives both the
# `keymesh` command, run on the hostile-input, contour and formats CLI tests
# and every fuzz corpus and regression file (tests/sanitized_cli.py), and
# the libFuzzer targets, each run for FUZZ_QUICK_SECONDS (0 skips them).
# One instrumented build instead of two (a gcc ASan build of keymesh, then
# the clang fuzz build) keeps CI's 2-core `make test` under its 25 minutes
# (docs/decisions/ci-time.md: where the time goes, and the command that measures it).
FUZZ_QUICK_SECONDS ?= 10
# ... and at most FUZZ_QUICK_RUNS inputs from seed 1, so that a green run is
# the same run on any machine as fast (a gate must not fail by chance).
FUZZ_QUICK_RUNS ?= 4000
# The DICOM target forks GDCM's child processes (src/io/child_process.hpp):
# about 6 inputs a second under ASan, so its gate is fewer inputs.
FUZZ_QUICK_RUNS_FORKING ?= 30
FORKING_FUZZ_TARGETS = dicom
sanitize-quick: deps
	@echo "make test: short sanitized run (ASan+UBSan keymesh and fuzzers, one clang build in build-fuzz)"
	@$(MAKE) --no-print-directory fuzz-build FUZZ_BUILD_FLAGS='-DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1"' FUZZ_TARGETS="keymesh keymesh_fuzzers"
	@$(SANITIZER_ENV) JOBS=$(JOBS) $(PYTHON) tests/sanitized_cli.py build-fuzz/keymesh
ifneq ($(FUZZ_QUICK_SECONDS),0)
	@$(MAKE) --no-print-directory fuzz-run FUZZ_SECONDS=$(FUZZ_QUICK_SECONDS) FUZZ_FLAGS="-seed=1 -runs=$(FUZZ_QUICK_RUNS)" \
	  FUZZ_FORKING_FLAGS="-runs=$(FUZZ_QUICK_RUNS_FORKING)"
endif

sanitize: deps
	@cmake -S . -B build-asan $(SANITIZE_CMAKE) -DKEYMESH_SANITIZE=address,undefined $(CMAKE_FLAGS) >/dev/null
	@cmake --build build-asan -j $(JOBS)
	@cd build-asan && $(SANITIZER_ENV) ctest --output-on-failure -j $(JOBS)
	@CC=clang-14 CXX=clang++-14 cmake -S . -B build-tsan $(SANITIZE_CMAKE) -DKEYMESH_SANITIZE=thread >/dev/null
	@cmake --build build-tsan -j $(JOBS) --target keymesh_tests
	@$(SANITIZER_ENV) build-tsan/keymesh_tests --gtest_filter='$(TSAN_FILTER)' --gtest_brief=1

# libFuzzer (clang 14): one executable per reader in build-fuzz (built with
# the poison of unwritten Array elements, as sanitize-quick's keymesh is),
# each run for FUZZ_SECONDS over a copy of its seed corpus (tests/fuzz/corpus/<target>),
# JOBS targets at a time (scripts/fuzz_run.sh);
# crashes are written to build-fuzz/crashes/<target>/ (add them to
# tests/fuzz/regressions/<target>/ once fixed; `make test` replays both).
FUZZ_SECONDS ?= 60
FUZZ_FLAGS ?= -rss_limit_mb=2048 -malloc_limit_mb=256 -timeout=10 -max_len=65536
# Forking targets: GDCM allocates what a damaged length field says (up to
# 4 GiB) in its child process, whose budget (RLIMIT_AS) is off under ASan;
# libFuzzer's malloc hook, inherited by the child, would write each as an
# oom-* artifact although keymesh reports the file (tests/fuzz/regressions/
# dicom/gdcm_allocates_a_length_field). The target's own reads stay under
# 1 MiB of planes (fuzz_checks.hpp).
FUZZ_FORKING_FLAGS ?= -malloc_limit_mb=8192
FUZZ_BUILD_FLAGS ?=
FUZZ_TARGETS ?= keymesh_fuzzers
fuzz: fuzz-build fuzz-run
fuzz-build: deps
	@CC=clang-14 CXX=clang++-14 cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DKEYMESH_FUZZ=ON \
	  -DCMAKE_CXX_FLAGS=-DKEYMESH_POISON_UNWRITTEN -DKEYMESH_BUILD_TESTS=OFF -DKEYMESH_BUILD_BENCH=OFF -DKEYMESH_PYTHON=OFF -DKEYMESH_CUDA=OFF $(CMAKE_FLAGS) $(FUZZ_BUILD_FLAGS) >/dev/null
	@cmake --build build-fuzz -j $(JOBS) --target $(FUZZ_TARGETS)
fuzz-run:
	@FUZZ_SECONDS='$(FUZZ_SECONDS)' FUZZ_FLAGS='$(FUZZ_FLAGS)' FUZZ_FORKING_FLAGS='$(FUZZ_FORKING_FLAGS)' \
	  FORKING_FUZZ_TARGETS='$(FORKING_FUZZ_TARGETS)' JOBS='$(JOBS)' bash scripts/fuzz_run.sh

clean:
	rm -rf $(BUILD_DIR) out build-asan build-asan-quick build-tsan build-fuzz
