#!/usr/bin/env bash
# Prints the path of a Python 3.11 interpreter (bpy 5.0.1 is built for exactly 3.11), or fails
# with a message saying how to get one.
set -euo pipefail
candidates=(python3.11 /usr/bin/python3.11 /usr/local/bin/python3.11 python3)
if command -v pyenv >/dev/null 2>&1; then
  while read -r v; do candidates+=("$(pyenv root)/versions/$v/bin/python3"); done < <(pyenv versions --bare 2>/dev/null | grep '^3\.11' || true)
fi
for c in "${candidates[@]}"; do
  p=$(command -v "$c" 2>/dev/null) || continue
  if "$p" -c 'import sys, venv; sys.exit(0 if sys.version_info[:2] == (3, 11) else 1)' 2>/dev/null; then
    echo "$p"; exit 0
  fi
done
echo "error: bvhlab needs Python 3.11 (bpy 5.0.1 requires exactly 3.11)." >&2
echo "       On Debian 12: apt-get install python3 python3-venv python3-dev (3.11 is the system Python)." >&2
exit 1
