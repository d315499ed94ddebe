#!/usr/bin/env bash
# Packs what scripts/gpu_check.sh needs on a bare GPU machine without network into build/gpu-check
# (about 50 MB): the release C++ Vulkan tests and the frame-time tool (build/cpp, `make cpp-test`
# builds them), the Vulkan loader, the Khronos validation layer and the C++ runtime of this
# machine; Debian's libglvnd, which the NVIDIA driver's Vulkan library needs (glvnd/); and for
# bench/render.py, wheels of the module and numpy for the GPU machine's Python (py/) and the
# atrium as .npz (scenes/). Carry build/gpu-check with the device call; see scripts/gpu_check.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
out=build/gpu-check
rm -rf "$out" && mkdir -p "$out/bin" "$out/lib" "$out/layers"
for t in test_vulkan test_vulkan_jobs vulkan_frame_times; do
    test -x "build/cpp/tests/cpp/$t" || { echo "build/cpp/tests/cpp/$t is missing: run make cpp-test first" >&2; exit 1; }
    cp "build/cpp/tests/cpp/$t" "$out/bin/"
done
lib=/usr/lib/x86_64-linux-gnu
cp -L "$lib/libvulkan.so.1" "$lib/libstdc++.so.6" "$lib/libgcc_s.so.1" "$lib/libVkLayer_khronos_validation.so" "$out/lib/"
cp /usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json "$out/layers/"
# The NVIDIA driver's manifest names libGLX_nvidia.so.0, which loads libGLdispatch (libglvnd): the
# first H200 machine had none ("Could not get 'vkCreateInstance' via 'vk_icdGetInstanceProcAddr'").
debs=$(mktemp -d) && chmod 777 "$debs"  # apt-get downloads as _apt
if (cd "$debs" && apt-get download -q libglvnd0 libegl1 libgl1 libglx0 libgles2 libopengl0 >/dev/null); then
    for d in "$debs"/*.deb; do dpkg-deb -x "$d" "$out/glvnd"; done
else
    echo "warning: no libglvnd packages (apt-get download failed): the GPU machine must have its own" >&2
fi
rm -rf "$debs"
# bench/render.py: a wheel of the module at this commit and numpy's, for the GPU machine's Python
# (GPU_PYTHON, default 3.12: the H200 machines' Ubuntu 24.04; a Python of that version must be
# installed here, e.g. by pyenv, or the check runs without the Python benchmark); gpu_check.sh
# unpacks them there. Both wheels of one Python only: a device call carries at most 64 MiB.
version=${GPU_PYTHON:-3.12}
python=
for p in "$HOME"/.pyenv/versions/"$version"*/bin/python"$version" "$(command -v "python$version" || true)"; do
    if [ -x "$p" ] && "$p" -c pass 2>/dev/null; then python=$p; break; fi  # (a pyenv shim may refuse)
done
if [ -n "$python" ]; then
    tag=cp${version/./}
    builder=$python
    if [ "$("$python" -c 'import sys; print(sys.prefix == sys.base_prefix)')" = True ]; then
        builder=build/venv-$tag/bin/python  # a venv with the build backend, outside that Python
        [ -x "$builder" ] || "$python" -m venv "build/venv-$tag"
        "$builder" -m pip install -q "scikit-build-core>=0.10" "nanobind>=2.0"
    fi
    mkdir -p "$out/py"
    "$builder" scripts/build_addon.py wheel --into "$out/py" >/dev/null
    .venv/bin/python -m pip download -q --only-binary=:all: --no-deps --python-version "$version" \
        --implementation cp --platform manylinux2014_x86_64 -d "$out/py" "numpy>=1.26,<2"
else
    echo "warning: no Python $version here: the bundle has no module for bench/render.py" >&2
fi
mkdir -p "$out/scenes"
.venv/bin/python -c "import sys; from bvhlab.library import load_scene; load_scene('atrium')[0].save(sys.argv[1])" \
    "$out/scenes/atrium.npz"
git rev-parse HEAD > "$out/commit"
du -sh "$out"
