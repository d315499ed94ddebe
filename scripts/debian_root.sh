#!/usr/bin/env bash
# A Debian root under build/SUITE with a real Blender binary and the Python it embeds, on a Debian
# 12 machine that has neither. `make test` uses two:
#   trixie  Debian 13: Blender 4.3 on Python 3.13; the cp313 wheel, the bpy module 5.2 LTS on Python
#           3.13 (a venv, /opt/py313), the bpy modules 5.3 and 5.1 (venvs /opt/bpy53 and /opt/bpy51:
#           blender.org's newest line and its first on Python 3.13) and the Blender binary checks
#           (headless and under Xvfb)
#   sid     Debian unstable: Blender 5.2 on Python 3.14, as Linux distributions build it (against
#           their system Python); the cp314 wheel and the Blender binary checks
#
#   scripts/debian_root.sh SUITE setup        create or update the root (each step once; stamp files)
#   scripts/debian_root.sh SUITE run CMD...   run CMD inside it, in the repository (mounted at /src)
#   scripts/debian_root.sh SUITE versions     the Blender and Python it holds, one line
#
# BVHLAB_TRIXIE / BVHLAB_SID put a root elsewhere. Set-up is incremental: debootstrap once, the
# Debian packages again only when the suite's list below changes, the venv again only when its
# requirements file changes. Mounts (/proc, /dev, /dev/pts, the repository) live in a private
# mount namespace (unshare), so they vanish with the process whatever happens.
#
# Pinning: the mirrors serve only each suite's current packages (no snapshot archive is reachable),
# so a root made later may hold other versions. EXPECT below is what the checks were written for;
# set-up stops with one line naming what the suite ships now when its Blender or Python major.minor
# differs (before downloading it), and records the exact versions in STAMPS/versions.
set -euo pipefail

ROOT_DIR=$(cd "$(dirname "$0")/.." && pwd)
SUITE=${1:-}
MIRROR=${BVHLAB_DEBIAN_MIRROR:-http://deb.debian.org/debian}

# What every root holds: the Blender binary and what it needs headless (its extension add-on
# imports cattrs and requests; GPU start-up aborts the process without EGL and Mesa); a compiler,
# CMake, the shader compiler, Vulkan headers, loader and lavapipe for the wheel (GCC 12 beside the
# suite's newer GCC, so the wheel asks for no newer libstdc++ than the cp311 one built on Debian
# 12: see MAX_GLIBCXX in tests/python/test_addon_install.py); for the UI run a virtual X server, a
# key press (close the splash) and a screen dump (xwd). PYTHON_PACKAGES (per suite) sit between.
BLENDER_PACKAGES=(blender python3-numpy python3-cattr python3-requests libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri)
BUILD_PACKAGES=(g++ g++-12 cmake ninja-build glslc libvulkan-dev libvulkan1 mesa-vulkan-drivers xvfb xdotool x11-apps ca-certificates)

case "$SUITE" in
  trixie)
    # pip builds the cp313 wheel in a venv that also holds the bpy module (requirements-py313.txt)
    PYTHON_PACKAGES=(python3-dev python3-venv)
    VENV=/opt/py313 REQUIREMENTS=requirements-py313.txt
    # the bpy modules 5.3 and 5.1 beside it (one bpy per venv): only the add-on checks run there
    EXTRA_VENVS=(/opt/bpy53=requirements-bpy53.txt /opt/bpy51=requirements-bpy51.txt)
    EXPECT_BLENDER=4.3 EXPECT_PYTHON=3.13
    ;;
  sid)
    # no bpy module for Python 3.14 on PyPI: the cp314 wheel is built with Debian's own build
    # backend (scikit-build-core, nanobind), pip wheel --no-build-isolation, no venv
    PYTHON_PACKAGES=(python3-dev python3-pip python3-nanobind python3-scikit-build-core)
    VENV="" REQUIREMENTS="" EXTRA_VENVS=()
    EXPECT_BLENDER=5.2 EXPECT_PYTHON=3.14
    ;;
  *)
    echo "usage: $0 trixie|sid setup | run CMD... | versions" >&2
    exit 2
    ;;
esac
shift
PACKAGES=("${BLENDER_PACKAGES[@]}" "${PYTHON_PACKAGES[@]}" "${BUILD_PACKAGES[@]}")
location_var=BVHLAB_${SUITE^^}
DIR=${!location_var:-$ROOT_DIR/build/$SUITE}
STAMPS=$DIR/.bvhlab-stamps

log() { echo "[$SUITE] $*" >&2; }

# The host's CA bundle (it may carry a site certificate) and name resolution, for apt and pip.
copy_host_files() {
  ln -sf /proc/self/mounts "$DIR/etc/mtab"
  cp -L /etc/resolv.conf "$DIR/etc/resolv.conf" 2>/dev/null || true
  mkdir -p "$DIR/etc/ssl/host"
  cp -L /etc/ssl/certs/ca-certificates.crt "$DIR/etc/ssl/host/ca-certificates.crt" 2>/dev/null || true
}

bootstrap() {
  [ -f "$STAMPS/base" ] && return
  "$ROOT_DIR/scripts/install_system_packages.sh" debootstrap
  # debian-archive-keyring on Debian 12 (2023.3+deb12u1 and later) carries trixie's signing keys,
  # which sign unstable too.
  local started=$SECONDS logfile=$DIR.debootstrap.log
  log "debootstrap $SUITE into $DIR (about a minute)"
  rm -rf "$DIR"
  mkdir -p "$(dirname "$DIR")"
  debootstrap --variant=minbase --keyring=/usr/share/keyrings/debian-archive-keyring.gpg \
    "$SUITE" "$DIR" "$MIRROR" >"$logfile" 2>&1 || { tail -20 "$logfile" >&2; exit 1; }
  mkdir -p "$STAMPS"
  touch "$STAMPS/base"
  log "debootstrap took $((SECONDS - started)) s"
}

stamp_of() { sha256sum | cut -c1-16; }

# "blender 5.2.2+dfsg-1 python3 3.14.8-1": the versions apt would install (Candidate) or has (Installed).
apt_versions() {
  local field=$1
  in_root "for p in blender python3; do printf '%s %s ' \$p \"\$(LC_ALL=C apt-cache policy \$p | sed -n 's/^ *$field: //p')\"; done"
}

# Stops with one line when the suite's Blender or Python moved from what the checks were written
# for. $1: "blender VERSION python3 VERSION" (a Debian version: an epoch and a revision may wrap it).
check_expected() {
  local blender python3
  read -r _ blender _ python3 _ <<<"$1"
  if [[ "${blender#*:}" != "$EXPECT_BLENDER".* || "${python3#*:}" != "$EXPECT_PYTHON".* ]]; then
    log "$SUITE now ships blender $blender with Python $python3; the checks were written for blender $EXPECT_BLENDER with Python $EXPECT_PYTHON (EXPECT_* in scripts/debian_root.sh)"
    exit 1
  fi
}

# The Blender binary's own version and the Python it embeds (distributions link the system one,
# but only the binary can tell), checked and kept in STAMPS/versions.
record_versions() {
  local embedded
  embedded=$(in_root "blender --background --factory-startup --python-expr \
    'import bpy, platform; print(\"EMBEDDED\", bpy.app.version_string.split()[0], platform.python_version())' \
    2>/dev/null | sed -n 's/^EMBEDDED //p'")
  check_expected "blender ${embedded% *} python3 ${embedded#* }"
  echo "$(apt_versions Installed)embeds Python ${embedded#* }" > "$STAMPS/versions"
}

install_packages() {
  local want started=$SECONDS
  want=$(printf '%s\n' "${PACKAGES[@]}" | stamp_of)
  [ "$(cat "$STAMPS/packages" 2>/dev/null)" = "$want" ] && return
  # A mirror may serve a Release file past its Valid-Until (unstable's is valid for a week, and the
  # one reached here was weeks old): the signature is still checked.
  echo 'Acquire::Check-Valid-Until "false";' > "$DIR/etc/apt/apt.conf.d/90bvhlab-valid-until"
  in_root "DEBIAN_FRONTEND=noninteractive apt-get update -qq"
  check_expected "$(apt_versions Candidate)"
  log "installing Debian packages in the root: ${PACKAGES[*]}"
  in_root "DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends ${PACKAGES[*]} >/dev/null \
    && apt-get clean"
  record_versions
  echo "$want" > "$STAMPS/packages"
  log "packages took $((SECONDS - started)) s: $(cat "$STAMPS/versions")"
}

python_venv() {
  [ -n "$VENV" ] || return 0
  one_venv "$VENV" "$REQUIREMENTS" venv
  local extra
  for extra in "${EXTRA_VENVS[@]}"; do one_venv "${extra%%=*}" "${extra#*=}" "venv-$(basename "${extra%%=*}")"; done
}

one_venv() {  # PATH REQUIREMENTS STAMP: a venv in the root with a requirements file, again when it changes
  local venv=$1 requirements=$2 stamp=$3 want
  want=$(stamp_of < "$ROOT_DIR/$requirements")
  [ "$(cat "$STAMPS/$stamp" 2>/dev/null)" = "$want" ] && return
  log "Python venv $venv with $requirements"
  in_root "test -x $venv/bin/python || python3 -m venv $venv; \
    $venv/bin/python -m pip install -q --upgrade pip && \
    $venv/bin/python -m pip install -q -r /src/$requirements"
  echo "$want" > "$STAMPS/$stamp"
}

# Run a shell command inside the root, in /src (the repository), with mounts that live only as
# long as the command. The venv (trixie) comes first on PATH.
in_root() {
  copy_host_files
  mkdir -p "$DIR/src"
  unshare --mount --propagation private -- bash -euo pipefail -c '
    root=$1 src=$2 path=$3 suite=$4; shift 4
    mounted=()
    cleanup() { for ((i=${#mounted[@]}-1; i>=0; i--)); do umount -l "${mounted[i]}" 2>/dev/null || true; done; }
    trap cleanup EXIT
    mount -t proc proc "$root/proc" && mounted+=("$root/proc")
    mount --bind /dev "$root/dev" && mounted+=("$root/dev")
    mount --bind /dev/pts "$root/dev/pts" && mounted+=("$root/dev/pts")
    mount --bind "$src" "$root/src" && mounted+=("$root/src")
    chroot "$root" /usr/bin/env -i HOME=/root LANG=C.UTF-8 TERM="${TERM:-dumb}" PATH="$path" \
      PIP_CERT=/etc/ssl/host/ca-certificates.crt PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_DEFAULT_TIMEOUT=180 \
      BVHLAB_DEBIAN_ROOT="$suite" ${BVHLAB_ROOT_ENV:-} \
      bash -euo pipefail -c "cd /src; $*"
  ' in_root "$DIR" "$ROOT_DIR" "${VENV:+$VENV/bin:}/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin" \
    "$SUITE" "$@"
}

case "${1:-}" in
  setup)
    bootstrap
    install_packages
    [ -f "$STAMPS/versions" ] || record_versions  # a root made before versions were recorded
    python_venv
    ;;
  run | versions)
    [ -f "$STAMPS/packages" ] || { log "no root yet (or set-up unfinished): scripts/debian_root.sh $SUITE setup"; exit 1; }
    if [ "$1" = versions ]; then cat "$STAMPS/versions" 2>/dev/null || apt_versions Installed; exit 0; fi
    shift
    in_root "$*"
    ;;
  *)
    echo "usage: $0 $SUITE setup | run CMD... | versions" >&2
    exit 2
    ;;
esac
