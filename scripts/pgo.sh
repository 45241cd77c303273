#!/usr/bin/env bash
# Profile-guided optimisation (gcc -fprofile-use) of the library and the program: the
# Makefile's `build` asks this script for the profile, then builds with it. The profile comes
# from an instrumented build run on a short version of the paper's flume (a dense packing with
# logs, the flow and the jam at a nearer dam, on two threads; a short packing on one thread),
# and is made again only when a source file changed (its id is a hash of the sources).
# the thirty-second performance pass (P32, in the git history) measured what it gains; the simulation is the same to the
# last bit (same state hash), only the compiled code's layout and inlining change.
#   usage: [PGO=0] bash scripts/pgo.sh BUILD_DIR   -> prints the CMake options that build with it
# (PGO=0: the options of the plain build, and nothing made)
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${PGO:-1}" != 1 ]; then
  echo "-DSD_PGO="
  exit 0
fi
build=${1:-build}
gen="$build-pgo"
prof="$(pwd)/$gen/profile"
id=$(cat CMakeLists.txt scripts/pgo.sh app/*.c include/*.h src/*.c src/*.h src/core/* src/geom/* | sha256sum | cut -c1-16)
if [ "$(cat "$prof/id" 2>/dev/null)" != "$id" ]; then
  echo "pgo: making the profile (instrumented build, ~1 minute of training runs)" >&2
  rm -rf "$prof" "$gen/train" "$gen"/train-*.log
  cmake -S . -B "$gen" -DCMAKE_BUILD_TYPE=Release -DSD_PGO=gen -DSD_PGO_DIR="$prof" >/dev/null
  cmake --build "$gen" -j "$(nproc)" --target sabodem >/dev/null
  flume=(examples/shibuya2009.yaml --set output.vtk=false --set output.png=false --set output.log_interval=0.05)
  # one training run: train NAME ARGS... (its output in $gen/train-NAME.log, shown if it fails)
  train() {
    local name=$1
    shift
    "$gen/sabodem" run "${flume[@]}" -o "$gen/train/$name" "$@" >"$gen/train-$name.log" 2>&1 ||
      { cat "$gen/train-$name.log" >&2; exit 1; }
  }
  # two threads (the paper's run): a dense pile with its logs, the flow, the jam at the dam
  OMP_PROC_BIND=true OMP_PLACES=cores train two --threads 2 --set flume.x_dam=1.0 --set flume.x_end=1.35 \
    --set phases.packing_time=0.5 --set phases.flow_limit=0.5 --set phases.capture_limit=0.25
  # one thread (the serial paths: the matrix's runs, the one-core bench)
  train one --threads 1 --set phases.packing_time=0.15 --set phases.flow_limit=0.01 --set phases.capture_limit=0.01
  echo "$id" > "$prof/id"
fi
echo "-DSD_PGO=use -DSD_PGO_DIR=$prof -DSD_PGO_ID=$id"
