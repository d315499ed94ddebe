# bvhlab — `make test` and `make demo` set up everything they need on a fresh Debian 12 machine
# (Debian packages, a Python 3.11 venv, the C++ build) and redo only what changed.
SHELL := /bin/bash
.DEFAULT_GOAL := help

VENV    ?= .venv
PY      := $(VENV)/bin/python
JOBS    ?= $(shell nproc)
CMAKE_GEN := -G Ninja

CORE_SOURCES := $(shell find core_cpp shaders -type f \( -name '*.cpp' -o -name '*.h' -o -name '*.txt' -o -name '*.comp' -o -name '*.glsl' -o -name '*.vert' -o -name '*.frag' \) 2>/dev/null)
PY_SOURCES   := $(shell find python -type f -name '*.py' 2>/dev/null)

.PHONY: help setup system venv build test cpp-test asan-test pytest demo bench addon scenes clean

help:
	@echo "make test   install what is missing, build, run all tests (C++, ASan/UBSan, pytest)"
	@echo "make demo   install what is missing, build, reproduce the report's Table 1 on the bundled atrium (out/demo)"
	@echo "make bench  build and traversal benchmark against Embree (bench/results/*.json)"
	@echo "make addon  the Blender extension zip in dist/"

setup: system venv

system:
	@scripts/install_system_packages.sh

venv: $(VENV)/.deps

$(VENV)/.deps: requirements-dev.txt | system
	@test -x $(PY) || { py=$$(scripts/find_python311.sh) && echo "Creating $(VENV) with $$py" && $$py -m venv $(VENV); }
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -r requirements-dev.txt
	@touch $@

# The Python package, installed editable; the C++ module is rebuilt incrementally in build/<tag>.
build: $(VENV)/.built
$(VENV)/.built: $(VENV)/.deps $(CORE_SOURCES) $(PY_SOURCES) CMakeLists.txt pyproject.toml
	$(PY) -m pip install -q --no-build-isolation --no-deps -e .
	@touch $@

build/cpp/build.ninja: CMakeLists.txt core_cpp/CMakeLists.txt tests/cpp/CMakeLists.txt | system
	cmake -S . -B build/cpp $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=Release -DBVHLAB_TESTS=ON > /dev/null
build/asan/build.ninja: CMakeLists.txt core_cpp/CMakeLists.txt tests/cpp/CMakeLists.txt | system
	cmake -S . -B build/asan $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBVHLAB_TESTS=ON -DBVHLAB_SANITIZE=ON > /dev/null

cpp-test: build/cpp/build.ninja
	cmake --build build/cpp -j $(JOBS)
	ctest --test-dir build/cpp --output-on-failure -j $(JOBS)

asan-test: build/asan/build.ninja
	cmake --build build/asan -j $(JOBS)
	ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --test-dir build/asan --output-on-failure -j $(JOBS)

pytest: build
	$(PY) -m pytest -q

test: cpp-test asan-test pytest

# The report's Table 1, its checks, charts, Figures 3-5 and level sheets for the bundled atrium,
# and the README's picture.
demo: build
	$(PY) -m bvhlab compare atrium --frames 3 --builds 5 --out out/demo
	$(PY) -m bvhlab render atrium --method sah12 --bvh-depth 8:9 --width 800 --height 600 --out docs/atrium_overlay.png

bench: build
	$(PY) bench/build.py
	$(PY) bench/traverse.py

# The Blender extension zip (dist/), with the compiled core as a bundled wheel.
addon: build
	$(PY) scripts/build_addon.py

# Regenerate the bundled .blend scenes.
scenes: build
	$(PY) blender_scenes/make_scenes.py

clean:
	rm -rf build dist out $(VENV)/.built
