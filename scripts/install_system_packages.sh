#!/usr/bin/env bash
# Installs the Debian packages bvhlab needs that are not installed yet (nothing when all are),
# and any further packages named as arguments (make bench: Embree 3's libembree-dev).
set -euo pipefail

packages=(
  # C++ build
  g++ cmake ninja-build libgtest-dev
  # Python 3.11 for bpy 5.0.1 (Debian 12's own python3 is 3.11)
  python3 python3-venv python3-dev
  # what bpy needs to load and to draw (without EGL/Mesa Blender aborts at GPU start-up)
  libx11-6 libxrender1 libxfixes3 libxi6 libxkbcommon0 libsm6 libice6 libgl1 libxext6
  libegl1 libegl-mesa0 libgl1-mesa-dri
  # Vulkan on lavapipe, the shader compiler and the validation layer
  mesa-vulkan-drivers libvulkan-dev glslc vulkan-validationlayers vulkan-tools libstb-dev
  # clang for the sanitizer build (GCC's UBSan lacks float-cast-overflow) and libFuzzer
  clang libclang-rt-14-dev
  # the Debian roots with real Blender binaries (scripts/debian_root.sh); here so that two roots
  # made at once do not both run apt
  debootstrap
  "$@"
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "Installing Debian packages: ${missing[*]}"
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "error: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
