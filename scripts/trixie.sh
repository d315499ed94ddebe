#!/usr/bin/env bash
# A Debian 13 (trixie) root under build/trixie: Python 3.13 and a real Blender binary (4.3.2) on a
# Debian 12 machine, which has neither. `make test` uses it for the cp313 wheel, the bpy module on
# Python 3.13 and the Blender binary checks (headless and under Xvfb).
#
#   scripts/trixie.sh setup          create or update the root (each step once; stamp files)
#   scripts/trixie.sh run CMD...     run CMD inside it, in the repository (mounted at /src)
#
# Set-up is incremental: debootstrap once, the Debian packages again only when the list below
# changes, the Python 3.13 venv (/opt/py313) again only when requirements-py313.txt changes.
# Mounts (/proc, /dev, /dev/pts, the repository) live in a private mount namespace (unshare), so
# they vanish with the process whatever happens; a trap unmounts them on every normal exit too.
set -euo pipefail

ROOT_DIR=$(cd "$(dirname "$0")/.." && pwd)
TRIXIE=${BVHLAB_TRIXIE:-$ROOT_DIR/build/trixie}
MIRROR=${BVHLAB_DEBIAN_MIRROR:-http://deb.debian.org/debian}
STAMPS=$TRIXIE/.bvhlab-stamps

PACKAGES=(
  # the Blender binary, and what it needs headless: its extension add-on imports cattrs and
  # requests; GPU start-up aborts the process without EGL and Mesa
  blender python3-numpy python3-cattr python3-requests libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri
  # the cp313 wheel: compiler, CMake, shader compiler, Vulkan headers and loader, lavapipe; GCC 12
  # beside Debian 13's GCC 14, so the wheel asks for no newer libstdc++ than the cp311 one built on
  # Debian 12 (Ubuntu 22.04's, for one: see MAX_GLIBCXX in tests/python/test_addon_install.py)
  python3-dev python3-venv g++ g++-12 cmake ninja-build glslc libvulkan-dev libvulkan1 mesa-vulkan-drivers
  # the UI run: a virtual X server, a key press (close the splash) and a screen dump (xwd)
  xvfb xdotool x11-apps
  ca-certificates
)

log() { echo "[trixie] $*" >&2; }

# The host's CA bundle (it may carry a site certificate) and name resolution, for apt and pip.
copy_host_files() {
  ln -sf /proc/self/mounts "$TRIXIE/etc/mtab"
  cp -L /etc/resolv.conf "$TRIXIE/etc/resolv.conf" 2>/dev/null || true
  mkdir -p "$TRIXIE/etc/ssl/host"
  cp -L /etc/ssl/certs/ca-certificates.crt "$TRIXIE/etc/ssl/host/ca-certificates.crt" 2>/dev/null || true
}

bootstrap() {
  [ -f "$STAMPS/base" ] && return
  command -v debootstrap >/dev/null || { log "installing debootstrap"; apt-get install -y -qq debootstrap >/dev/null; }
  # debian-archive-keyring on Debian 12 (2023.3+deb12u1 and later) carries trixie's signing keys.
  log "debootstrap trixie into $TRIXIE (about a minute)"
  rm -rf "$TRIXIE"
  mkdir -p "$(dirname "$TRIXIE")"
  debootstrap --variant=minbase --keyring=/usr/share/keyrings/debian-archive-keyring.gpg \
    trixie "$TRIXIE" "$MIRROR" >"$(dirname "$TRIXIE")/debootstrap.log" 2>&1 \
    || { tail -20 "$(dirname "$TRIXIE")/debootstrap.log" >&2; exit 1; }
  mkdir -p "$STAMPS"
  touch "$STAMPS/base"
}

stamp_of() { sha256sum | cut -c1-16; }

install_packages() {
  local want
  want=$(printf '%s\n' "${PACKAGES[@]}" | stamp_of)
  [ "$(cat "$STAMPS/packages" 2>/dev/null)" = "$want" ] && return
  log "installing Debian packages in the root: ${PACKAGES[*]}"
  in_root "DEBIAN_FRONTEND=noninteractive apt-get update -qq && DEBIAN_FRONTEND=noninteractive \
    apt-get install -y -qq --no-install-recommends ${PACKAGES[*]} >/dev/null && apt-get clean"
  echo "$want" > "$STAMPS/packages"
}

python_venv() {
  local want
  want=$(cat "$ROOT_DIR/requirements-py313.txt" | stamp_of)
  [ "$(cat "$STAMPS/venv" 2>/dev/null)" = "$want" ] && return
  log "Python 3.13 venv /opt/py313 with requirements-py313.txt (bpy 5.x for Python 3.13)"
  in_root "test -x /opt/py313/bin/python || python3 -m venv /opt/py313; \
    /opt/py313/bin/python -m pip install -q --upgrade pip && \
    /opt/py313/bin/python -m pip install -q -r /src/requirements-py313.txt"
  echo "$want" > "$STAMPS/venv"
}

# Run a shell command inside the root, in /src (the repository), with mounts that live only as
# long as the command.
in_root() {
  copy_host_files
  mkdir -p "$TRIXIE/src"
  unshare --mount --propagation private -- bash -euo pipefail -c '
    root=$1 src=$2; shift 2
    mounted=()
    cleanup() { for ((i=${#mounted[@]}-1; i>=0; i--)); do umount -l "${mounted[i]}" 2>/dev/null || true; done; }
    trap cleanup EXIT
    mount -t proc proc "$root/proc" && mounted+=("$root/proc")
    mount --bind /dev "$root/dev" && mounted+=("$root/dev")
    mount --bind /dev/pts "$root/dev/pts" && mounted+=("$root/dev/pts")
    mount --bind "$src" "$root/src" && mounted+=("$root/src")
    chroot "$root" /usr/bin/env -i HOME=/root LANG=C.UTF-8 TERM="${TERM:-dumb}" \
      PATH=/opt/py313/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
      PIP_CERT=/etc/ssl/host/ca-certificates.crt PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_DEFAULT_TIMEOUT=180 \
      BVHLAB_IN_TRIXIE=1 ${BVHLAB_ROOT_ENV:-} \
      bash -euo pipefail -c "cd /src; $*"
  ' in_root "$TRIXIE" "$ROOT_DIR" "$@"
}

case "${1:-}" in
  setup)
    bootstrap
    install_packages
    python_venv
    ;;
  run)
    shift
    [ -f "$STAMPS/base" ] || { log "no root yet: scripts/trixie.sh setup"; exit 1; }
    in_root "$*"
    ;;
  *)
    echo "usage: $0 setup | run CMD..." >&2
    exit 2
    ;;
esac
