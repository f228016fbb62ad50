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
  pybind11-dev python3-dev python3-pytest python3-skimage python3-meshio \
  clang-14 libfuzzer-14-dev libclang-rt-14-dev

.PHONY: all deps build demo test bench clean

all: build

# Installs the missing Debian packages when run as root, otherwise says which
# ones to install.
deps:
	@missing=""; for p in $(DEBIAN_PACKAGES); do \
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

demo: build
	@$(PYTHON) scripts/demo.py --keymesh $(BUILD_DIR)/keymesh --out out

test: build
	@cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

bench: build
	@$(PYTHON) bench/run.py --build $(BUILD_DIR) $(if $(QUICK),--quick,)

clean:
	rm -rf $(BUILD_DIR) out
