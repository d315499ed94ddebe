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

# The Debian roots (scripts/debian_root.sh), each with a real Blender binary and the Python it
# embeds: trixie (Debian 13: Blender 4.3 on Python 3.13, and the bpy 5.2 module) and sid (Debian
# unstable: Blender 5.2 on Python 3.14, a distribution build linked to the system Python).
TRIXIE    := scripts/debian_root.sh trixie
SID       := scripts/debian_root.sh sid
ADDON_SOURCES := $(shell find addon -type f -not -path '*/__pycache__/*' -not -path 'addon/wheels/*' 2>/dev/null)
WHEEL_INPUTS  := $(CORE_SOURCES) $(PY_SOURCES) CMakeLists.txt pyproject.toml scripts/wheel_glibc_compat.h \
                 $(wildcard blender_scenes/*.blend blender_scenes/scenes.json)

.PHONY: help setup system venv bpy45-venv bpy50-venv trixie sid build check check-pytest test cpp-test scalar-test asan-test pytest blender-test \
        bpy313-test bpy53-test bpy51-test bpy50-test bpy45-test \
        blender-binary-test blender-ui-test blender-sid-test blender-sid-ui-test demo bench addon screenshots scenes clean

help:
	@echo "make test         install what is missing, build, run all tests (C++, ASan/UBSan, pytest on bpy 4.2,"
	@echo "                  the add-on checks on bpy 4.5 and 5.0 (Python 3.11), 5.1, 5.2 and 5.3 (Python 3.13), real Blender"
	@echo "                  binaries 4.3 (Python 3.13) and 5.2 (Python 3.14)"
	@echo "                  headless and with their UI)"
	@echo "make check        the quick loop: lint, C++ tests, pytest without the slow tests (no Debian roots)"
	@echo "make demo         install what is missing, build, reproduce the report's Table 1 on Crytek Sponza (out/demo),"
	@echo "                  and the update policies frame by frame over two animated .blend files (out/animate)"
	@echo "make bench        build and traversal benchmark against Embree (bench/results/*.json)"
	@echo "make addon        the Blender extension zip in dist/ (wheels for Python 3.11, 3.13 and 3.14)"
	@echo "make screenshots  the sidebar panel and the Rendered viewport in a real Blender window → docs/panel.png, docs/viewport.png"
	@echo "make fuzz         libFuzzer over the core for FUZZ_SECONDS (default 300) under ASan/UBSan"
	@echo "make lint         ruff, mypy and clang-format checks (make format applies the formatters)"

setup: system venv trixie sid

# Each created once and updated only when its package list or requirements file change (stamps);
# the two are independent of each other.
trixie: | system
	@$(TRIXIE) setup
sid: | system
	@$(SID) setup

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

# The test builds ask for the Vulkan backend outright (its tests are only added where it is
# built): a machine without glslc or the Vulkan headers fails here instead of testing less.
build/cpp/build.ninja: CMakeLists.txt core_cpp/CMakeLists.txt tests/cpp/CMakeLists.txt | system
	cmake -S . -B build/cpp $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=Release -DBVHLAB_TESTS=ON -DBVHLAB_VULKAN=ON > /dev/null
build/asan/build.ninja: CMakeLists.txt core_cpp/CMakeLists.txt tests/cpp/CMakeLists.txt | system
	cmake -S . -B build/asan $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBVHLAB_TESTS=ON -DBVHLAB_VULKAN=ON -DBVHLAB_SANITIZE=ON > /dev/null

cpp-test: build/cpp/build.ninja
	cmake --build build/cpp -j $(JOBS)
	ctest --test-dir build/cpp --output-on-failure -j $(JOBS)

asan-test: build/asan/build.ninja
	cmake --build build/asan -j $(JOBS)
	ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --test-dir build/asan --output-on-failure -j $(JOBS)

# The plain C++ path of CPUs without SSE (core_cpp/CMakeLists.txt BVHLAB_SCALAR), built and tested
# on this x86-64 machine: every C++ test but the Vulkan ones.
build/scalar/build.ninja: CMakeLists.txt core_cpp/CMakeLists.txt tests/cpp/CMakeLists.txt | system
	cmake -S . -B build/scalar $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=Release -DBVHLAB_TESTS=ON -DBVHLAB_SCALAR=ON -DBVHLAB_VULKAN=OFF -DBVHLAB_PYTHON=OFF > /dev/null

scalar-test: build/scalar/build.ninja
	cmake --build build/scalar -j $(JOBS)
	ctest --test-dir build/scalar --output-on-failure -j $(JOBS)

# bpy 4.2 LTS (Python 3.11, the oldest supported line) in .venv; the zip's install test needs dist/.
pytest: build addon
	$(PY) -m pytest -q --durations=0 --durations-min=3

# The add-on checks (tests/blender/run.py) on the zip, in the Debian 13 root: the bpy module 5.2 LTS
# on Python 3.13, the Blender binary headless, and the Blender binary with its UI under Xvfb; in the
# sid root, its Blender 5.2 on Python 3.14 headless and with its UI.
bpy313-test: addon
	$(TRIXIE) run python tests/blender/run.py --zip dist/bvhlab.zip
# The same checks on the newest line of each Python: bpy 5.3 (Python 3.13, a venv of the root's
# own) and bpy 5.0 (Python 3.11); and on the lines between: 5.1 (blender.org's first on Python
# 3.13, the root's third venv) and 4.5 LTS, the last 4.x line (Python 3.11). Each Python 3.11 bpy
# has a venv of its own beside .venv's 4.2 LTS: build/venv-bpy45, build/venv-bpy50 (one per
# requirements-bpyNN.txt).
bpy51-test bpy53-test: bpy%-test: addon
	$(TRIXIE) run /opt/bpy$*/bin/python tests/blender/run.py --zip dist/bvhlab.zip
build/venv-bpy%/.deps: requirements-bpy%.txt | system
	@test -x $(@D)/bin/python || { py=$$(scripts/find_python311.sh) && $$py -m venv $(@D); }
	$(@D)/bin/python -m pip install -q --upgrade pip
	$(@D)/bin/python -m pip install -q -r $<
	@touch $@
bpy45-venv bpy50-venv: bpy%-venv: build/venv-bpy%/.deps
bpy45-test bpy50-test: bpy%-test: addon build/venv-bpy%/.deps
	build/venv-bpy$*/bin/python tests/blender/run.py --zip dist/bvhlab.zip
blender-binary-test: addon
	$(TRIXIE) run blender --background --factory-startup --python-exit-code 1 --python tests/blender/run.py -- --zip dist/bvhlab.zip
blender-ui-test: addon
	$(TRIXIE) run python tests/blender/ui/run_ui.py --zip dist/bvhlab.zip --out build/ui
blender-sid-test: addon
	$(SID) run blender --background --factory-startup --python-exit-code 1 --python tests/blender/run.py -- --zip dist/bvhlab.zip
# Without the panel scenario: its label widths come from UILayout.introspect(), which in Debian's
# Blender 5.2.2 on Python 3.14 corrupts Python's memory (a draw hook calling it, then making a dict,
# segfaults Blender with no add-on enabled; 4.3 on Python 3.13 is fine).
blender-sid-ui-test: addon
	$(SID) run python3 tests/blender/ui/run_ui.py --zip dist/bvhlab.zip --out build/ui-sid --only build_cancel build_races viewport pick undo
blender-test: bpy313-test bpy53-test bpy51-test bpy50-test bpy45-test blender-binary-test blender-ui-test blender-sid-test blender-sid-ui-test

# clang with ASan, UBSan and float-cast-overflow (GCC's -fsanitize=undefined has no float→int
# check); its ctest also replays the fuzz corpus (tests/fuzz/corpus) under them.
.PHONY: clang-sanitize-test fuzz
CLANG := -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++
build/clang-asan/build.ninja: CMakeLists.txt core_cpp/CMakeLists.txt tests/cpp/CMakeLists.txt tests/fuzz/CMakeLists.txt | system
	cmake -S . -B build/clang-asan $(CMAKE_GEN) $(CLANG) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBVHLAB_TESTS=ON -DBVHLAB_VULKAN=ON -DBVHLAB_SANITIZE=ON > /dev/null

clang-sanitize-test: build/clang-asan/build.ninja
	cmake --build build/clang-asan -j $(JOBS)
	ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --test-dir build/clang-asan --output-on-failure -j $(JOBS)

# libFuzzer over build + intersect + refit + boxes (tests/fuzz/fuzz_core.cpp) for FUZZ_SECONDS,
# growing build/fuzz/corpus from the seeds; crashes land in build/fuzz/crashes/ (add the ones
# fixed to tests/fuzz/corpus, where make test replays them).
FUZZ_SECONDS ?= 300
build/fuzz/build.ninja: CMakeLists.txt core_cpp/CMakeLists.txt tests/fuzz/CMakeLists.txt | system
	cmake -S . -B build/fuzz $(CMAKE_GEN) $(CLANG) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBVHLAB_TESTS=ON -DBVHLAB_SANITIZE=ON -DBVHLAB_FUZZ=ON -DBVHLAB_VULKAN=OFF > /dev/null

fuzz: build/fuzz/build.ninja
	cmake --build build/fuzz --target fuzz_core -j $(JOBS)
	mkdir -p build/fuzz/corpus build/fuzz/crashes
	UBSAN_OPTIONS=print_stacktrace=1 build/fuzz/tests/fuzz/fuzz_core -max_total_time=$(FUZZ_SECONDS) -timeout=20 \
		-artifact_prefix=build/fuzz/crashes/ build/fuzz/corpus tests/fuzz/corpus

# Lint: ruff (pycodestyle, pyflakes, import order, bugbear, pyupgrade) and its formatter over every
# Python file, mypy over the package (settings in pyproject.toml), clang-format over every C++ file
# (.clang-format). `make format` applies both formatters.
PY_LINT_DIRS := python addon tests bench blender_scenes scripts examples
CPP_FILES = $(shell git ls-files '*.cpp' '*.h' '*.inl' 2>/dev/null || find core_cpp tests bench shaders -name '*.cpp' -o -name '*.h' -o -name '*.inl')
.PHONY: lint format
lint: $(VENV)/.deps
	$(VENV)/bin/ruff check $(PY_LINT_DIRS)
	$(VENV)/bin/ruff format --check $(PY_LINT_DIRS)
	$(VENV)/bin/mypy
	@echo "clang-format --dry-run --Werror (every C++ file)"
	@$(VENV)/bin/clang-format --dry-run --Werror $(CPP_FILES)

format: $(VENV)/.deps
	$(VENV)/bin/ruff format $(PY_LINT_DIRS)
	$(VENV)/bin/clang-format -i $(CPP_FILES)

# The inner loop (a few minutes from a built tree): lint, the release C++ tests, and pytest on Python
# 3.11 (bpy 4.2, lavapipe) without the tests marked slow, the zip installed being one with the
# cp311 wheel alone (no Debian root needed). `make test` runs everything; CI runs make test.
# Markers to select by hand: vulkan, bpy, slow, full_zip (tests/python/conftest.py).
CHECK_ZIP := build/check/bvhlab.zip
check: build lint cpp-test check-pytest
check-pytest: build $(CHECK_ZIP)
	BVHLAB_ZIP=$(CHECK_ZIP) $(PY) -m pytest -q -m "not slow and not full_zip" --durations=5
$(CHECK_ZIP): build/wheels/.cp311 $(ADDON_SOURCES) scripts/build_addon.py
	cp "$$($(PY) scripts/build_addon.py package --tags cp311 --output-dir build/check)" $@

# The GPU check's bundle (build/gpu-check: the C++ Vulkan tests, the loader, the validation layer,
# libglvnd, wheels of the module and numpy for bench/render.py, the atrium), for a GPU machine
# without network: carry build/gpu-check and run scripts/gpu_check.sh there (one call, ~4 minutes).
.PHONY: gpu-bundle
gpu-bundle: build/cpp/build.ninja
	cmake --build build/cpp -j $(JOBS)
	scripts/gpu_bundle.sh

# Every stage, timed (scripts/test_stages.sh: the Debian roots are set up in the background while
# the C++ stages compile; the table of stage times is printed at the end, build/test-times.txt).
test:
	@scripts/test_stages.sh

# The report's Table 1 on its own scene, Crytek Sponza (frame times on the CPU reference, the
# report's build settings), its claims checked with the measurement protocol, the §4.1 overlay claim
# and Figure 5 on the CPU reference and Vulkan, charts, Figures 3-6 and level sheets (out/demo);
# the README's pictures (docs/). Then issue 34's per-frame experiment on the two animated .blend
# files, made by bpy (blender_scenes/make_animated.py: a 250K-triangle wave deformed by geometry
# nodes; 300 knots flying through the atrium as instances), every update policy over their 24
# frames (out/animate/{wave,crowd}/animate.csv, .json, .png; the plots to docs/animate_*.png).
ANIMATE_OUT := out/animate
demo: build
	$(PY) -m bvhlab compare sponza --backend cpu --out out/demo
	cp out/demo/figure6.png docs/sponza_figure6.png
	cp out/demo/times.png docs/sponza_times.png
	cp out/demo/sah_per_depth.png docs/sponza_sah_per_depth.png
	cp out/demo/leaf_sizes.png docs/sponza_leaf_sizes.png
	cp out/demo/figure5_overlay_vulkan.png docs/figure5_overlay.png 2>/dev/null || cp out/demo/figure5_overlay_cpu.png docs/figure5_overlay.png
	$(PY) -m bvhlab render atrium --method sah12 --bvh-depth 8:9 --width 800 --height 600 --out docs/atrium_overlay.png
	$(PY) blender_scenes/make_animated.py --out $(ANIMATE_OUT)
	$(PY) -m bvhlab animate $(ANIMATE_OUT)/wave_anim.blend --out $(ANIMATE_OUT)/wave
	$(PY) -m bvhlab animate $(ANIMATE_OUT)/crowd_anim.blend --out $(ANIMATE_OUT)/crowd
	cp $(ANIMATE_OUT)/wave/animate.png docs/animate_wave.png
	cp $(ANIMATE_OUT)/crowd/animate.png docs/animate_crowd.png

# The README's example sweep: the bundled scenes and a mesh file in each format trimesh reads
# (examples/study/make_files.py writes them), on a Dask LocalCluster; out/study/summary.md.
.PHONY: study
study: build
	$(PY) examples/study/make_files.py
	$(PY) -m bvhlab sweep examples/study/study.toml --out out/study

# Embree 3 in C++ (Debian's libembree-dev) is the benchmarks' peer; bench/cpp builds without it otherwise.
bench: build
	@scripts/install_system_packages.sh libembree-dev
	$(PY) bench/build.py
	$(PY) bench/traverse.py

# The Blender extension zip (dist/bvhlab.zip, a copy of dist/bvhlab-<version>.zip) with a wheel for
# each Python Blender embeds: cp311 built here, cp313 in the Debian 13 root, cp314 in the sid root.
addon: dist/bvhlab.zip
build/wheels/.cp311: $(VENV)/.deps $(WHEEL_INPUTS)
	$(PY) scripts/build_addon.py wheel
	@touch $@
build/wheels/.cp313: $(WHEEL_INPUTS) | trixie
	$(TRIXIE) run CXX=g++-12 python scripts/build_addon.py wheel
	@touch $@
build/wheels/.cp314: $(WHEEL_INPUTS) | sid
	$(SID) run CXX=g++-12 python3 scripts/build_addon.py wheel
	@touch $@
dist/bvhlab.zip: build/wheels/.cp311 build/wheels/.cp313 build/wheels/.cp314 $(ADDON_SOURCES) scripts/build_addon.py
	cp "$$($(PY) scripts/build_addon.py package)" $@

# The sidebar panel and the render engine's Rendered viewport in a real Blender window (Xvfb) →
# docs/panel.png, docs/viewport.png.
screenshots: addon
	$(TRIXIE) run python tests/blender/ui/run_ui.py --zip dist/bvhlab.zip --out build/ui --screenshots docs

# Regenerate the bundled .blend scenes.
scenes: build
	$(PY) blender_scenes/make_scenes.py

clean:
	rm -rf build/cpp build/asan build/wheel* build/wheels build/addon-stage dist out $(VENV)/.built  # keeps build/trixie, build/sid
