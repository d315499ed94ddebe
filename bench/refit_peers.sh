#!/usr/bin/env bash
# Refit against rebuild on one core, bvhlab beside tinybvh (bench/cpp/refit_peers.cpp says what is
# measured). Needs build/cpp (make cpp-test); BVHLAB_TINYBVH_DIR=<folder with tiny_bvh.h> adds
# tinybvh. Prints JSON; with --json also writes bench/results/refit.json.
set -euo pipefail
cd "$(dirname "$0")/.."
out=build/refit_peers
flags=(-O3 -std=c++20 -ffp-contract=off -Icore_cpp/include -Ishaders)
if [[ -n "${BVHLAB_TINYBVH_DIR:-}" ]]; then
  flags+=(-march=haswell -DBVHLAB_TINYBVH -I"$BVHLAB_TINYBVH_DIR" -w)
else
  flags+=(-march=x86-64-v2)
fi
c++ "${flags[@]}" bench/cpp/refit_peers.cpp build/cpp/core_cpp/libbvhlab_core.a -lpthread -o "$out"
if [[ "${1:-}" == "--json" ]]; then "$out" | tee bench/results/refit.json; else "$out"; fi
