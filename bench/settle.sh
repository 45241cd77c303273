#!/usr/bin/env bash
# The settled sphere bed both codes start from (bench/run.sh, bench/portable.sh): the SPEC §8
# packing of ../shared/reference/lammps/gen_particles.py (seed 12345), dropped and settled once
# by LAMMPS (20,000 + 60,000 steps), written to DEST as a LAMMPS data file.
#   usage: bash bench/settle.sh DEST   (LAMMPS from scripts/setup.sh --bench)
set -euo pipefail
dest=${1:?usage: bash bench/settle.sh DEST}
cd "$(dirname "$0")/.."
ref=$PWD/../shared/reference/lammps
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 "$ref/gen_particles.py" spec "$work/init.data" 12345 >/dev/null
(cd "$work" && OMP_NUM_THREADS=1 lmp -in "$ref/flume.in" -var data init.data -var ndrop 20000 \
    -var nsettle 60000 -var ndense 0 -var nflow 0 -log settle.log >/dev/null)
cp "$work/settled_lammps.data" "$dest"
