#!/usr/bin/env bash
# `make test`: every stage of the suite, each timed, the table of times printed at the end and
# kept in build/test-times.txt (so that the README's figure stays true).
#
# The two Debian roots (scripts/debian_root.sh: debootstrap, apt, pip; mostly network and disk)
# are set up in the background from the start, while the C++ stages compile on the cores; the
# stages that need a root wait for it. Every stage runs even when one before it failed (one run
# shows every failure); the exit status is 1 when any failed. Each stage's output goes to the
# terminal as it runs; the background set-ups write to build/test-logs/.
set -uo pipefail
cd "$(dirname "$0")/.."

JOBS=${JOBS:-$(nproc)}
LOGS=build/test-logs
mkdir -p "$LOGS"
names=() seconds=() results=()
started_all=$(date +%s)

record() {  # NAME START RC
  names+=("$1") seconds+=($(( $(date +%s) - $2 ))) results+=("$([ "$3" = 0 ] && echo ok || echo "FAILED ($3)")")
}

stage() {  # NAME MAKE-TARGET...
  local name=$1 start rc
  shift
  echo "==== stage: $name" >&2
  start=$(date +%s)
  make --no-print-directory "$@" JOBS="$JOBS"
  rc=$?
  record "$name" "$start" "$rc"
  return "$rc"
}

# Set-up everything else needs (Debian packages, the venv); without it nothing can run.
stage "setup: packages, venv" system venv || { echo "set-up failed" >&2; exit 1; }

# The roots, in the background: one make each (they are independent of each other).
background() {  # NAME TARGET
  ( start=$(date +%s); make --no-print-directory "$2" >"$LOGS/$2.log" 2>&1; echo "$? $(( $(date +%s) - start ))" >"$LOGS/$2.done" ) &
}
rm -f "$LOGS"/*.done
background "root: Debian 13" trixie
background "root: Debian sid" sid
background "venv: bpy 5.0" bpy50-venv
background "venv: bpy 4.5 LTS" bpy45-venv

wait_for() {  # TARGET NAME: wait for a background set-up; record its time (its own, not the wait)
  local start
  start=$(date +%s)
  while [ ! -f "$LOGS/$1.done" ]; do sleep 2; done
  read -r rc took <"$LOGS/$1.done"
  names+=("$2 (background; waited $(( $(date +%s) - start )) s)") seconds+=("$took")
  results+=("$([ "$rc" = 0 ] && echo ok || echo "FAILED ($rc): see $LOGS/$1.log")")
  [ "$rc" = 0 ] || tail -20 "$LOGS/$1.log" >&2
  return "$rc"
}

failed=0
stage "lint" lint || failed=1
stage "C++ tests (release)" cpp-test || failed=1
stage "C++ tests (plain C++ path)" scalar-test || failed=1
stage "C++ tests (GCC ASan+UBSan)" asan-test || failed=1
stage "C++ tests (clang ASan+UBSan, fuzz corpus)" clang-sanitize-test || failed=1
roots=0
wait_for trixie "root: Debian 13" || roots=1
wait_for sid "root: Debian sid" || roots=1
wait_for bpy50-venv "venv: bpy 5.0 (Python 3.11)" || roots=1
wait_for bpy45-venv "venv: bpy 4.5 LTS (Python 3.11)" || roots=1
if [ "$roots" = 0 ]; then
  stage "extension zip (cp311, cp313, cp314 wheels)" addon || failed=1
  stage "pytest (Python 3.11, bpy 4.2, lavapipe)" pytest || failed=1
  stage "add-on checks: bpy 5.2 module (Python 3.13)" bpy313-test || failed=1
  stage "add-on checks: bpy 5.3 module (Python 3.13)" bpy53-test || failed=1
  stage "add-on checks: bpy 5.1 module (Python 3.13)" bpy51-test || failed=1
  stage "add-on checks: bpy 5.0 module (Python 3.11)" bpy50-test || failed=1
  stage "add-on checks: bpy 4.5 LTS module (Python 3.11)" bpy45-test || failed=1
  stage "add-on checks: Blender 4.3 binary, headless" blender-binary-test || failed=1
  stage "add-on checks: Blender 4.3 binary, window" blender-ui-test || failed=1
  stage "add-on checks: Blender 5.2 (sid, Python 3.14), headless" blender-sid-test || failed=1
  stage "add-on checks: Blender 5.2 (sid, Python 3.14), window" blender-sid-ui-test || failed=1
else
  failed=1
fi

{
  echo "make test stage times ($(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores, JOBS=$JOBS)"
  for i in "${!names[@]}"; do printf '%6d s  %-60s %s\n' "${seconds[$i]}" "${names[$i]}" "${results[$i]}"; done
  printf '%6d s  %s\n' "$(( $(date +%s) - started_all ))" "in all (wall clock)"
} | tee build/test-times.txt
exit "$failed"
