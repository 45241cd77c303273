#!/usr/bin/env bash
# Speed of this tree against another revision, in the same hour, interleaved: bench/run.sh's
# side-by-side flume (the settled sphere bed, dense then flowing) with LAMMPS, the revision
# and this tree run in turn, REPEAT times on one core and on two. Both builds are made as
# `make build` makes them (guided by their own profile, scripts/pgo.sh). Prints, per thread
# count, the medians and each engine's ratio to LAMMPS; the new over the old is the change's
# speed. Results go to bench/results/compare.txt.
#   usage: bash bench/compare.sh REV [REPEAT] [NDENSE] [NFLOW]
set -euo pipefail
rev=${1:?usage: bash bench/compare.sh REV [REPEAT] [NDENSE] [NFLOW]}
REPEAT=${2:-3}
NDENSE=${3:-10000}
NFLOW=${4:-50000}
cd "$(dirname "$0")/.."
bash scripts/setup.sh --bench
here=$PWD
base=$(mktemp -d /tmp/sabodem-compare.XXXXXX)
work=$(mktemp -d)
trap 'git -C "$here" worktree remove --force "$base/tree" >/dev/null 2>&1 || true; rm -rf "$base" "$work"' EXIT
# the revision's tree beside this one (../shared is found from either: both sit one level down)
git worktree add --detach "$base/tree" "$rev" >/dev/null
ln -s "$here/../shared" "$base/shared"
build() { # $1: tree
  (cd "$1" && pgo=$(bash scripts/pgo.sh build) &&
    cmake -S . -B build-bench -DCMAKE_BUILD_TYPE=Release $pgo >/dev/null &&
    cmake --build build-bench -j "$(nproc)" --target bench_flume >/dev/null)
}
build "$base/tree"
build "$here"
ref=../shared/reference/lammps
bash bench/settle.sh "$work/settled.data"
. bench/common.sh
out=bench/results/compare.txt
{
  echo "machine: $(lscpu | awk -F: '/Model name/ {gsub(/^ +/,"",$2); print $2}'), $(nproc) cores; $(date -u '+%Y-%m-%d %H:%M UTC')"
  echo "old: $(git -C "$base/tree" log -1 --format='%h %s' | cut -c1-100)"
  echo "new: $(git log -1 --format='%h %s' | cut -c1-100)$(git diff --quiet || echo ' (with uncommitted changes)')"
} | tee "$out"
for p in 1 2; do
  : > "$work/l$p"; : > "$work/o$p"; : > "$work/n$p"
  for r in $(seq "$REPEAT"); do
    sleep 3
    if [ "$p" -eq 1 ]; then
      (cd "$work" && OMP_NUM_THREADS=1 $pin lmp -in "$here/$ref/flume.in" -var data settled.data -var ndrop 0 \
        -var nsettle 0 -var ndense "$NDENSE" -var nflow "$NFLOW" -log run.log >/dev/null)
    else
      (cd "$work" && OMP_NUM_THREADS=1 mpirun --allow-run-as-root -np 2 --bind-to core lmp -in "$here/$ref/flume.in" \
        -var data settled.data -var ndrop 0 -var nsettle 0 -var ndense "$NDENSE" -var nflow "$NFLOW" -log run.log >/dev/null)
    fi
    lammps_rates "$work/run.log" >> "$work/l$p"
    # the two engines in turn, the order alternating between repeats
    for which in $([ $((r % 2)) -eq 1 ] && echo "o n" || echo "n o"); do
      tree=$here
      [ "$which" = o ] && tree=$base/tree
      sleep 3
      $([ "$p" -eq 1 ] && echo "$pin" || echo "$bind") "$tree/build-bench/bench_flume" "$work/settled.data" 0 0 \
        "$NDENSE" "$NFLOW" --threads "$p" --t-reset 1e9 > "$work/sab.txt"
      awk '/^PHASE dense/ {d=$9} /^PHASE flow/ {f=$9} END {print d, f}' "$work/sab.txt" >> "$work/$which$p"
    done
  done
  ld=$(awk '{print $1}' "$work/l$p" | median); lf=$(awk '{print $2}' "$work/l$p" | median)
  od=$(awk '{print $1}' "$work/o$p" | median); of=$(awk '{print $2}' "$work/o$p" | median)
  nd=$(awk '{print $1}' "$work/n$p" | median); nf=$(awk '{print $2}' "$work/n$p" | median)
  awk -v p="$p" -v r="$REPEAT" -v ld="$ld" -v lf="$lf" -v od="$od" -v of="$of" -v nd="$nd" -v nf="$nf" 'BEGIN {
    printf "%d thread(s)/rank(s), medians of %d (particle-steps/s): LAMMPS dense %.3e flow %.3e | old %.3e %.3e (%.2fx / %.2fx LAMMPS) | new %.3e %.3e (%.2fx / %.2fx) | new/old %.3f / %.3f\n",
      p, r, ld, lf, od, of, od / ld, of / lf, nd, nf, nd / ld, nf / lf, nd / od, nf / of }' | tee -a "$out"
  paste "$work/o$p" "$work/n$p" | awk -v p="$p" '{printf "%d thread(s), repeat %d: new/old dense %.3f flow %.3f\n", p, NR, $3 / $1, $4 / $2}' | tee -a "$out"
done
