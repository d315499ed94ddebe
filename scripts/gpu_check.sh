#!/usr/bin/env bash
# The GPU check (run on a GPU machine from the repository root, with build/gpu-check carried:
# scripts/gpu_bundle.sh makes it here). Runs the C++ Vulkan tests (every image against the CPU
# reference, zero validation errors, bounded dispatches), the frame-time tool, and bench/render.py
# (the report's Table 1: Sponza and the atrium at 800×600, stack and stackless, and the CPU
# reference's wide traversal beside, against the report's frame times) on the GPU's driver, under 8 minutes; writes logs, gtest XML and the
# benchmark's JSON into $OUT (or build/gpu-check/out).
set -uo pipefail
bundle=build/gpu-check
out=${OUT:-$bundle/out}
mkdir -p "$out"
out=$(cd "$out" && pwd)
test -d "$bundle/bin" || { echo "no $bundle: run scripts/gpu_bundle.sh on the build machine and carry it" >&2; exit 2; }
export LD_LIBRARY_PATH="$PWD/$bundle/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export VK_LAYER_PATH="$PWD/$bundle/layers"
# libglvnd for the NVIDIA driver's libGLX_nvidia.so.0, where the machine has none (gpu_bundle.sh)
if ! ldconfig -p | grep -q libGLdispatch.so.0 && [ -d "$bundle/glvnd" ]; then
    LD_LIBRARY_PATH="$LD_LIBRARY_PATH:$PWD/$bundle/glvnd/usr/lib/x86_64-linux-gnu"
fi
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
# bench/render.py with the bundle's wheels unpacked (the machine's python3 must be the version
# they were built for: gpu_bundle.sh's GPU_PYTHON).
wheel=$(ls "$bundle"/py/bvhlab-*.whl 2>/dev/null | head -n 1)
tag=$(python3 -c 'import sys; print("cp%d%d" % sys.version_info[:2])' 2>/dev/null)
if [ -z "$wheel" ] || [ -z "$tag" ] || [[ "$wheel" != *-"$tag"-* ]]; then
    echo "bench/render.py: not run (python3 ${tag:-missing}, bundle wheel ${wheel:-none})" | tee -a "$out/summary.txt"
    exit $status
fi
site=$(mktemp -d)
for w in "$bundle"/py/*.whl; do python3 -m zipfile -e "$w" "$site"; done
for scene in sponza "$bundle/scenes/atrium.npz"; do
    name=$(basename "$scene" .npz)
    start=$SECONDS
    PYTHONPATH="$site" PYTHONUNBUFFERED=1 timeout 150 python3 bench/render.py --scene "$scene" --frames 3 \
        --json "$out/render_$name.json" > "$out/render_$name.log" 2>&1
    rc=$?
    [ $rc -eq 0 ] || status=1
    echo "bench/render.py $name: exit $rc in $((SECONDS - start)) s" | tee -a "$out/summary.txt"
    grep -v "^  \[" "$out/render_$name.log" | tail -n 40 >> "$out/summary.txt"  # the tables, not the progress
done
exit $status
