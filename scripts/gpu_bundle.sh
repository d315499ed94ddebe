#!/usr/bin/env bash
# Packs what scripts/gpu_check.sh needs on a bare GPU machine without network into build/gpu-check
# (about 30 MB): the release C++ Vulkan tests and the frame-time tool (build/cpp, `make cpp-test`
# builds them), the Vulkan loader, the Khronos validation layer and the C++ runtime of this
# machine. Carry build/gpu-check with the device call; see scripts/gpu_check.sh.
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
git rev-parse HEAD > "$out/commit"
du -sh "$out"
