#!/usr/bin/env bash
# Side-by-side benchmark: sabodem and LAMMPS (Debian, gran/hooke/history) on the same initial
# packing of the sphere-only flume (4619 spheres, SPEC §8 split, paper's springs, Δt = 1e-5 s),
# in the same phases: dense settled bed at rest behind the gate, then flowing after the gate
# is removed. Reports particle-steps per second (median of REPEAT runs) and the ratio, for
# 1 and 2 threads / ranks; then the scaling benchmark. Results go to bench/results/; the
# machine's own share of a two-thread step (bench_machine) first, to machine.txt.
#   usage: [PGO=0] bash bench/run.sh [REPEAT] [NDENSE] [NFLOW]
set -euo pipefail
cd "$(dirname "$0")/.."
REPEAT=${1:-3}
NDENSE=${2:-10000}
# flow: 50,000 steps (0.5 s after the gate opens, the pile spreading down the flume), the
# flowing phase of ../shared/reference/lammps/README.md's example, where LAMMPS's figures in the
# issue (9.4e6 one rank) were taken; the first 10,000 steps alone are still a dense pile
NFLOW=${3:-50000}
bash scripts/setup.sh --bench
# the library as `make build` makes it: guided by the profile of scripts/pgo.sh (the main build's,
# made first if need be); PGO=0 for the plain build
pgo=$(bash scripts/pgo.sh build)
cmake -S . -B build-bench -DCMAKE_BUILD_TYPE=Release $pgo >/dev/null
cmake --build build-bench -j "$(nproc)" --target bench_flume bench_scale bench_machine >/dev/null
out=bench/results
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ref=../shared/reference/lammps
# settle once with LAMMPS (drop + settle); both codes then start from this settled bed
bash bench/settle.sh "$work/settled.data"

. bench/common.sh
echo "machine: $(lscpu | awk -F: '/Model name/ {gsub(/^ +/,"",$2); print $2}'), $(nproc) cores" | tee "$out/side_by_side.txt"
# what the machine itself takes from two threads this hour (interruptions, both CPUs busy, a
# barrier a step), before the codes run
env OMP_PROC_BIND=true OMP_PLACES=cores ./build-bench/bench_machine 2 | tee "$out/machine.txt"
for p in 1 2; do
  : > "$work/l$p"; : > "$work/s$p"
  for r in $(seq "$REPEAT"); do
    # a pause before each timed run of either code: right after a two-rank LAMMPS run, a
    # two-thread sabodem run measured 5-10 % slower than after 20 s of rest (this VM)
    sleep 3
    if [ "$p" -eq 1 ]; then
      (cd "$work" && OMP_NUM_THREADS=1 $pin lmp -in "$OLDPWD/$ref/flume.in" -var data settled.data -var ndrop 0 -var nsettle 0 \
          -var ndense "$NDENSE" -var nflow "$NFLOW" -log run.log >/dev/null)
    else
      (cd "$work" && OMP_NUM_THREADS=1 mpirun --allow-run-as-root -np 2 --bind-to core lmp -in "$OLDPWD/$ref/flume.in" \
          -var data settled.data -var ndrop 0 -var nsettle 0 -var ndense "$NDENSE" -var nflow "$NFLOW" -log run.log >/dev/null)
    fi
    lammps_rates "$work/run.log" >> "$work/l$p"
    # the same neighbour policy as flume.in (rebuild when something moved half the skin); the
    # paper's extra rebuild every t_reset = 1 ms (SPEC §4) is timed separately below
    sleep 3
    # two threads pinned one per core (OpenMP's OMP_PROC_BIND), as mpirun --bind-to core pins
    # the two LAMMPS ranks
    $([ "$p" -eq 1 ] && echo "$pin" || echo "$bind") ./build-bench/bench_flume "$work/settled.data" 0 0 "$NDENSE" "$NFLOW" --threads "$p" --t-reset 1e9 > "$work/sab.txt"
    awk '/^PHASE dense/ {d=$9} /^PHASE flow/ {f=$9} END {print d, f}' "$work/sab.txt" >> "$work/s$p"
  done
  ld=$(awk '{print $1}' "$work/l$p" | median); lf=$(awk '{print $2}' "$work/l$p" | median)
  sd=$(awk '{print $1}' "$work/s$p" | median); sf=$(awk '{print $2}' "$work/s$p" | median)
  printf "%d thread(s)/rank(s), median of %d: dense  sabodem %.3e  LAMMPS %.3e  ratio %.2f | flow  sabodem %.3e  LAMMPS %.3e  ratio %.2f  (particle-steps/s)\n" \
    "$p" "$REPEAT" "$sd" "$ld" "$(awk -v a="$sd" -v b="$ld" 'BEGIN {print a / b}')" "$sf" "$lf" \
    "$(awk -v a="$sf" -v b="$lf" 'BEGIN {print a / b}')" | tee -a "$out/side_by_side.txt"
  # each repeat's own ratio (the two codes run back to back): how far one invocation's ratio
  # can move on a shared machine
  paste "$work/s$p" "$work/l$p" | awk -v p="$p" 'NR == 1 {dl = dh = $1 / $3; fl = fh = $2 / $4}
    {d = $1 / $3; f = $2 / $4; dl = d < dl ? d : dl; dh = d > dh ? d : dh; fl = f < fl ? f : fl; fh = f > fh ? f : fh}
    END {printf "%d thread(s)/rank(s), ratio of each repeat: dense %.2f-%.2f | flow %.2f-%.2f (lowest-highest of %d)\n", p, dl, dh, fl, fh, NR}' |
    tee -a "$out/side_by_side.txt"
done
cat "$work/sab.txt" >> "$out/side_by_side.txt"
# sabodem alone with the paper's rebuild interval (t_reset = 1 ms), for the record
for p in 1 2; do
  : > "$work/t$p"
  for r in $(seq "$REPEAT"); do
    $([ "$p" -eq 1 ] && echo "$pin" || echo "$bind") ./build-bench/bench_flume "$work/settled.data" 0 0 "$NDENSE" "$NFLOW" --threads "$p" > "$work/sab.txt"
    awk '/^PHASE dense/ {d=$9} /^PHASE flow/ {f=$9} END {print d, f}' "$work/sab.txt" >> "$work/t$p"
  done
  printf "sabodem with t_reset = 1 ms, %d thread(s), median of %d: dense %.3e flow %.3e (particle-steps/s)\n" "$p" "$REPEAT" \
    "$(awk '{print $1}' "$work/t$p" | median)" "$(awk '{print $2}' "$work/t$p" | median)" | tee -a "$out/side_by_side.txt"
done
# cost per particle-step against N: the same settled bed tiled to 1e3 .. 1e6 spheres
$pin ./build-bench/bench_scale "$work/settled.data" 2000 --big --threads 1 | tee "$out/scaling.txt"
$bind ./build-bench/bench_scale "$work/settled.data" 2000 --big --threads 2 | tee -a "$out/scaling.txt"
# the same with every sphere in the same surroundings at every N: copies of one settled unit of
# ~1000 spheres, each in its own walls (the contacts per sphere do not change with N)
$pin ./build-bench/bench_scale "$work/settled.data" 2000 --big --same --threads 1 | tee "$out/scaling_same.txt"
$bind ./build-bench/bench_scale "$work/settled.data" 2000 --big --same --threads 2 | tee -a "$out/scaling_same.txt"
