#!/usr/bin/env bash
# Install the Debian packages sabodem needs, only those missing (idempotent). Used by the
# README's quick start, the Makefile and CI alike.
set -euo pipefail
pkgs=(build-essential cmake pkg-config libyaml-dev libcjson-dev python3 python3-matplotlib python3-numpy libopenmpi-dev openmpi-bin)
if [ "${1:-}" = "--bench" ]; then pkgs+=(lammps openmpi-bin); fi
# bench/work.sh: callgrind and its client requests' header
if [ "${1:-}" = "--work" ]; then pkgs+=(valgrind); fi
# make fuzz (scripts/fuzz.sh): clang with libFuzzer and the sanitizers' runtime, OpenMP for clang
if [ "${1:-}" = "--fuzz" ]; then pkgs+=(clang libclang-rt-dev libomp-dev); fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
