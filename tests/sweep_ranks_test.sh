#!/usr/bin/env bash
# A sweep shared by several processes gives the same results.csv as one process: under
# `mpirun -np 3` (oversubscribed; skipped, saying so, when the build or the machine has no MPI),
# by hand with --shard U/N then --collect, and through the Slurm job array that `--emit slurm`
# writes (each task run as Slurm would, with SLURM_ARRAY_TASK_ID set). The sweep is 2 layouts x
# 2 log counts x 2 seeds of the reduced flume with branching (4 shared flows, 8 runs). Only the
# timing columns may differ. Also: the emitted scripts quote a hostile output path, bad --shard
# values are refused, and --collect over an unfinished sweep says how many runs are missing.
set -u
bin="$1"
mpi="${2:-OFF}" # ON when the program was built with MPI
src_dir="$(cd "$(dirname "$0")/.." && pwd)"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
pass=0
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL $*"; fail=$((fail + 1)); }

cat > "$tmp/small.yaml" <<EOF2
base: $src_dir/examples/flume_small.yaml
runs: 2
vary:
  dam.l_v: [0.040, 0]
  logs.count: [0, 4]
set:
  output.png: false
  output.vtk: false
  flume.x_dam: 0.5
  flume.x_end: 0.6
  phases.packing_time: 0.25
  phases.capture_limit: 0.25
EOF2

# results.csv of two sweeps equal but for the timing columns (and both with 8 rows)
same_results() {
  python3 - "$1" "$2" <<'PY'
import csv, sys
def load(p):
    rows = list(csv.DictReader(open(p)))
    return [{k: v for k, v in r.items() if k not in ("wall_s", "flow_wall_s")} for r in rows]
a, b = load(sys.argv[1]), load(sys.argv[2])
sys.exit(0 if len(a) == 8 and a == b else 1)
PY
}

"$bin" sweep "$tmp/small.yaml" -o "$tmp/one" --parallel 1 > "$tmp/one.log" 2>&1
code=$?
if [ "$code" -eq 0 ] && [ "$(wc -l < "$tmp/one/results.csv")" -eq 9 ]; then ok; else bad "one process (exit $code)"; cat "$tmp/one.log"; fi

# MPI ranks
if [ "$mpi" = "ON" ] && command -v mpirun > /dev/null; then
  # (under the sanitizers: Open MPI's own allocations, some from plugins it has unloaded by exit,
  # read as leaks, so LeakSanitizer is off for the ranks; the --shard runs below check ours)
  ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" \
    OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_mpi_warn_on_fork=0 \
    mpirun --oversubscribe -np 3 "$bin" sweep "$tmp/small.yaml" -o "$tmp/mpi" > "$tmp/mpi.log" 2>&1
  code=$?
  shards=$(grep -c "^sweep: shard [012] of 3:" "$tmp/mpi.log")
  if [ "$code" -eq 0 ] && same_results "$tmp/one/results.csv" "$tmp/mpi/results.csv" && [ "$shards" -ge 6 ] \
     && [ -f "$tmp/mpi/cases.csv" ]; then ok; else bad "mpirun -np 3 (exit $code, $shards shard lines)"; cat "$tmp/mpi.log"; fi
else
  echo "SKIP mpirun: the program was built without MPI or mpirun is missing (scripts/setup.sh installs Open MPI)"
fi

# by hand: three shards, then collect
for u in 0 1 2; do "$bin" sweep "$tmp/small.yaml" -o "$tmp/hand" --shard "$u/3" --parallel 1 > "$tmp/hand$u.log" 2>&1 || bad "shard $u/3"; done
if [ -e "$tmp/hand/results.csv" ]; then bad "a shard wrote results.csv"; else ok; fi
"$bin" sweep "$tmp/small.yaml" -o "$tmp/hand" --collect > "$tmp/collect.log" 2>&1
code=$?
if [ "$code" -eq 0 ] && same_results "$tmp/one/results.csv" "$tmp/hand/results.csv"; then ok; else bad "--shard + --collect (exit $code)"; cat "$tmp/collect.log"; fi

# --collect over an unfinished sweep: the runs it has, exit 1, the count of the missing ones
"$bin" sweep "$tmp/small.yaml" -o "$tmp/part" --shard 1/4 --parallel 1 > /dev/null 2>&1
"$bin" sweep "$tmp/small.yaml" -o "$tmp/part" --collect > "$tmp/part.log" 2>&1
code=$?
if [ "$code" -eq 1 ] && grep -q "6 of 8 runs have not finished" "$tmp/part.log" && [ "$(wc -l < "$tmp/part/results.csv")" -eq 3 ]; then ok
else bad "collect unfinished (exit $code)"; cat "$tmp/part.log"; fi

# Slurm: the emitted job array run task by task as Slurm would, then the collect job; the output
# path holds a quote and a command substitution that must stay text
sl="$tmp/sl'\$(touch $tmp/INJECTED)x"
(cd "$tmp" && "$bin" sweep small.yaml -o "$sl" --emit slurm > "$tmp/emit.log" 2>&1)
code=$?
units=$(grep -vc '^#' "$sl/slurm/units.txt" 2>/dev/null)
if [ "$code" -eq 0 ] && [ "$units" -eq 4 ] && grep -q '^#SBATCH --array=0-3$' "$sl/slurm/array.sh" && [ ! -d "$sl/runs" ]; then ok
else bad "emit slurm (exit $code, $units units)"; cat "$tmp/emit.log"; fi
for u in 0 1 2 3; do SLURM_ARRAY_TASK_ID=$u bash "$sl/slurm/array.sh" > "$tmp/task$u.log" 2>&1 || bad "array task $u"; done
bash "$sl/slurm/collect.sh" > "$tmp/slcollect.log" 2>&1
code=$?
if [ "$code" -eq 0 ] && same_results "$tmp/one/results.csv" "$sl/results.csv" && [ ! -e "$tmp/INJECTED" ]; then ok
else bad "slurm tasks + collect (exit $code)"; cat "$tmp/slcollect.log"; fi

# bad values
for s in 3/3 -1/2 1/0 x 1/2x; do
  "$bin" sweep "$tmp/small.yaml" -o "$tmp/bad" --shard "$s" > "$tmp/bad.log" 2>&1
  code=$?
  if [ "$code" -eq 2 ] && grep -q -- "--shard" "$tmp/bad.log" && [ ! -e "$tmp/bad" ]; then ok; else bad "--shard $s (exit $code)"; fi
done
"$bin" sweep "$tmp/small.yaml" -o "$tmp/bad" --emit pbs > "$tmp/bad.log" 2>&1
if [ $? -eq 2 ] && grep -q "slurm" "$tmp/bad.log"; then ok; else bad "--emit pbs"; fi
"$bin" sweep "$tmp/small.yaml" -o "$tmp/bad" --collect --shard 0/2 > "$tmp/bad.log" 2>&1
if [ $? -eq 2 ]; then ok; else bad "--collect with --shard"; fi

echo "sweep_ranks: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
