#!/usr/bin/env bash
# The Debian 13 root: scripts/debian_root.sh trixie (one definition for every suite's root), kept
# under this name for the commands that use it (scripts/trixie.sh setup | run CMD...).
exec "$(dirname "$0")/debian_root.sh" trixie "$@"
