#!/usr/bin/env bash
# The GPU check (run on a GPU machine from the repository root, with build/gpu-check carried:
# scripts/gpu_bundle.sh makes it here). Runs the C++ Vulkan tests (every image against the CPU
# reference, zero validation errors, bounded dispatches) and the frame-time tool on the GPU's
# driver, under 8 minutes; writes logs and gtest XML into $OUT (or build/gpu-check/out).
set -uo pipefail
bundle=build/gpu-check
out=${OUT:-$bundle/out}
mkdir -p "$out"
test -d "$bundle/bin" || { echo "no $bundle: run scripts/gpu_bundle.sh on the build machine and carry it" >&2; exit 2; }
export LD_LIBRARY_PATH="$PWD/$bundle/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export VK_LAYER_PATH="$PWD/$bundle/layers"
# The NVIDIA driver's manifest, wherever this machine keeps it (never lavapipe: the tests pin that
# only when VK_DRIVER_FILES is unset).
if [ -z "${VK_DRIVER_FILES:-}" ]; then
    for icd in /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json /usr/share/vulkan/icd.d/nvidia_icd.json \
               /etc/vulkan/icd.d/nvidia_icd.json /usr/share/vulkan/icd.d/nvidia_icd.x86_64.json; do
        if [ -f "$icd" ]; then export VK_DRIVER_FILES=$icd; break; fi
    done
fi
{
    echo "commit $(cat $bundle/commit)  date $(date -u +%FT%TZ)"
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1 || echo "no nvidia-smi"
    echo "VK_DRIVER_FILES=${VK_DRIVER_FILES:-unset}"
} | tee "$out/summary.txt"
[ -n "${VK_DRIVER_FILES:-}" ] || { echo "no NVIDIA Vulkan driver manifest found" | tee -a "$out/summary.txt"; exit 2; }
status=0
for t in test_vulkan test_vulkan_jobs; do
    start=$SECONDS
    timeout 200 "$bundle/bin/$t" --gtest_output="xml:$out/$t.xml" > "$out/$t.log" 2>&1
    rc=$?
    [ $rc -eq 0 ] || status=1
    echo "$t: exit $rc in $((SECONDS - start)) s; $(grep -E '^\[  (PASSED|FAILED)  \]' "$out/$t.log" | tr '\n' ' ')" | tee -a "$out/summary.txt"
    grep -E '^\[  FAILED  \] [A-Za-z]' "$out/$t.log" | head -20 | tee -a "$out/summary.txt"
    grep -m1 '^device:' "$out/$t.log" | tee -a "$out/summary.txt"
done
timeout 120 "$bundle/bin/vulkan_frame_times" > "$out/frame_times.log" 2>&1
echo "vulkan_frame_times: exit $?" | tee -a "$out/summary.txt"
tail -n 15 "$out/frame_times.log" | tee -a "$out/summary.txt"
exit $status
