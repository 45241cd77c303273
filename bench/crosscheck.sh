#!/usr/bin/env bash
# Cross-check of bulk quantities with LAMMPS (Debian, gran/hooke/history): the same random
# packing (../shared/reference/lammps/gen_particles.py spec, 4619 spheres) dropped and settled
# behind the gate by both codes, then released for a flow phase. Compared: mean and 95th
# percentile of the centre heights of the settled bed, sphere-sphere contacts per sphere, and
# the front (max x) after the flow phase. Writes bench/results/crosscheck.txt.
#   usage: bash bench/crosscheck.sh [NDROP] [NSETTLE] [NFLOW]
set -euo pipefail
cd "$(dirname "$0")/.."
NDROP=${1:-20000}
NSETTLE=${2:-60000}
NFLOW=${3:-20000}
bash scripts/setup.sh --bench
cmake -S . -B build-bench -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build-bench -j "$(nproc)" --target bench_flume >/dev/null
out=bench/results
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ref=../shared/reference/lammps
python3 "$ref/gen_particles.py" spec "$work/init.data" 12345 >/dev/null
(cd "$work" && OMP_NUM_THREADS=1 lmp -in "$OLDPWD/$ref/flume.in" -var data init.data -var ndrop "$NDROP" \
    -var nsettle "$NSETTLE" -var ndense 0 -var nflow "$NFLOW" -log lmp.log >/dev/null)
./build-bench/bench_flume "$work/init.data" "$NDROP" "$NSETTLE" 0 "$NFLOW" --threads 1 \
    --write-settled "$work/settled_sabodem.data" > "$work/sab.txt"
python3 - "$work" "$NDROP" "$NSETTLE" "$NFLOW" <<'PY' | tee "$out/crosscheck.txt"
import sys
work, ndrop, nsettle, nflow = sys.argv[1], *map(int, sys.argv[2:])

def heights(path):
    z, on = [], False
    for line in open(path):
        if line.startswith("Atoms"):
            on = True
            continue
        if on:
            f = line.split()
            if not f:
                continue
            if f[0][0].isalpha():
                break
            z.append(float(f[6]))
    z.sort()
    return sum(z) / len(z), z[int(0.95 * (len(z) - 1))], len(z)

# LAMMPS thermo: step atoms ke rke cnave xmax cpu; the last line before each "Loop time"
last, ends = None, []
for line in open(f"{work}/lmp.log"):
    f = line.split()
    if len(f) == 7 and f[0].isdigit():
        last = f
    if line.startswith("Loop time"):
        ends.append(last)
l_cn, l_xmax = float(ends[1][4]), float(ends[3][5])
l_mz, l_z95, n = heights(f"{work}/settled_lammps.data")
s = {}
for line in open(f"{work}/sab.txt"):
    f = line.split()
    if f and f[0] == "BULK":
        s[f[1]] = {f[k]: float(f[k + 1]) for k in range(2, len(f) - 1, 2)}
s_mz, s_z95 = s["settle"]["mean_z"], s["settle"]["z95"]
s_cn, s_xmax = s["settle"]["contacts_per_sphere"], s["flow"]["xmax"]
print(f"{n} spheres, drop {ndrop} + settle {nsettle} steps, then flow {nflow} steps (dt 1e-5 s)")
print(f"{'quantity':34s} {'LAMMPS':>9s} {'sabodem':>9s} {'diff':>8s}")
for name, a, b in [("settled bed: mean centre height (m)", l_mz, s_mz),
                   ("settled bed: 95% centre height (m)", l_z95, s_z95),
                   ("sphere-sphere contacts per sphere", l_cn, s_cn),
                   (f"front x after {nflow * 1e-5:.2f} s of flow (m)", l_xmax, s_xmax)]:
    print(f"{name:34s} {a:9.4f} {b:9.4f} {100 * (b - a) / a:+7.1f}%")
PY
