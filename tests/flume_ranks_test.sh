#!/usr/bin/env bash
# One run over N ranks (issue 54 item 2, docs/decomposition.md): the reduced flume, shortened
# (dam at 0.2 m, dt 40 us, 0.05 s packing, the capture 0.04 s: 4900 steps with the gate's
# removal, the flow, the pipes' arrival and their loads), run with --decompose in one process
# (the reference: one slab) and under mpirun -np 1, 2, 3 and 4 (oversubscribed):
#  1. every run gives the reference's state hash, P_V, series.csv, pipes.csv, trajectories.csv,
#     series.pvd, every VTK snapshot and summary.json (but for wall times and the decomposition's
#     own numbers), byte for byte; with 2 to 4 ranks bodies migrated and the boundaries moved;
#     periodic checkpoints change no bit;
#  2. a periodic checkpoint written by 2 ranks restarts on 3 ranks and on one process, the
#     flow-end checkpoint of 2 ranks on 4 ranks: the reference's hash and outputs again;
#  3. the one-process run without --decompose reads such a checkpoint and finishes.
# A build without MPI runs what needs no mpirun: the reference, its checkpoints, a restart of
# its own in one process, and 3.
set -u
bin="$1"
mpi_built="${2:-ON}"
src_dir="$(cd "$(dirname "$0")/.." && pwd)"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
bad() { echo "FAIL $*"; fail=$((fail + 1)); }
scen="$src_dir/examples/flume_small.yaml"
sets=(--set solver.dt=4e-5 --set phases.packing_time=0.05 --set phases.flow_limit=0.2 --set phases.capture_limit=0.04
      --set phases.quiet_time=0.01 --set flume.x_dam=0.2 --set flume.x_end=0.3 --set output.png=false
      --set output.vtk=true --set output.snapshot_interval=0.1 --set "output.trajectory_ids=[0, 7, 100]"
      --set output.trajectory_interval=0.004 --threads 1)
ck=(--set output.checkpoint_interval=0.03)
export SD_PREFETCH=off OMP_NUM_THREADS=1 OMPI_MCA_mpi_yield_when_idle=1
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# (under the sanitizers: Open MPI's own allocations read as leaks, slabs_mpi_test.sh)
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
mpi() { local n=$1; shift; mpirun --oversubscribe -np "$n" "$@"; }
field() { /usr/bin/python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
for k in sys.argv[2].split('.'):
    d = d[k]
print(d)" "$1" "$2" 2>/dev/null; }
# the summary without what depends on the wall clock, the restart or the ranks (and the
# checkpoints' interval, which changes no bit)
summary_core() {
  /usr/bin/python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
for k in ('wall_time_s', 'phase_wall_s', 'timers_s', 'front_prefetch', 'restarted_from', 'restart_flow_wall_s',
          'decomposition'):
    d.pop(k, None)
d.get('parameters', {}).pop('output.checkpoint_interval', None)
print(json.dumps(d, sort_keys=True))" "$1"
}
# same DIR: every output of DIR equals the reference's
same() {
  local d=$1 what=$2 f
  [ "$(field "$d/summary.json" state_hash)" = "$ref" ] || { bad "$what: state hash $(field "$d/summary.json" state_hash)"; return; }
  for f in series.csv pipes.csv trajectories.csv series.pvd; do
    cmp -s "$tmp/ref/$f" "$d/$f" || bad "$what: $f differs"
  done
  for f in "$tmp"/ref/*.vtp; do
    cmp -s "$f" "$d/$(basename "$f")" || bad "$what: $(basename "$f") differs"
  done
  [ "$(summary_core "$tmp/ref/summary.json")" = "$(summary_core "$d/summary.json")" ] || bad "$what: summary.json differs"
}

"$bin" run "$scen" -o "$tmp/ref" "${sets[@]}" --decompose > "$tmp/ref.log" 2>&1 || { bad "reference run"; cat "$tmp/ref.log"; }
ref=$(field "$tmp/ref/summary.json" state_hash)
pv=$(field "$tmp/ref/summary.json" trap_ratio)
echo "reference (--decompose, one process): hash $ref, P_V $pv, $(tail -n +2 "$tmp/ref/pipes.csv" | wc -l) pipe rows"
[ -n "$ref" ] && [ -n "$pv" ] && [ "$(awk -F, 'NR > 1 && $8 > 0' "$tmp/ref/pipes.csv" | wc -l)" -gt 0 ] ||
  bad "the reference has no hash, P_V or pipe load"

# 1. one process with periodic checkpoints, and 1 to 4 ranks (the 2 ranks' flow-end checkpoint too)
"$bin" run "$scen" -o "$tmp/ck" "${sets[@]}" "${ck[@]}" --decompose > "$tmp/ck.log" 2>&1 || bad "run with checkpoints"
same "$tmp/ck" "periodic checkpoints"
ranks=(1 2 3 4)
[ "$mpi_built" = "ON" ] || ranks=()
for n in "${ranks[@]}"; do
  extra=()
  [ "$n" -eq 1 ] && extra=(--decompose)
  [ "$n" -eq 2 ] && extra=(--checkpoint-at flow_end)
  if mpi "$n" "$bin" run "$scen" -o "$tmp/np$n" "${sets[@]}" "${ck[@]}" "${extra[@]}" > "$tmp/np$n.log" 2>&1; then
    same "$tmp/np$n" "mpirun -np $n"
  else
    bad "mpirun -np $n exited $?"
    tail -20 "$tmp/np$n.log"
  fi
  mig=$(field "$tmp/np$n/summary.json" decomposition.migrations)
  mov=$(field "$tmp/np$n/summary.json" decomposition.boundary_moves)
  echo "mpirun -np $n: hash $(field "$tmp/np$n/summary.json" state_hash), P_V $(field "$tmp/np$n/summary.json" trap_ratio), $mig migrations, $mov boundary moves"
  if [ "$n" -gt 1 ] && ! { [ "${mig:-0}" -gt 0 ] && [ "${mov:-0}" -gt 0 ]; }; then bad "-np $n: nothing migrated or moved"; fi
done

# 2. restarts on other rank counts
src=np2
[ "$mpi_built" = "ON" ] || src=ck
first=$(ls "$tmp/$src"/checkpoint_*.ckpt 2>/dev/null | sort | head -n 1)
[ -n "$first" ] || bad "no periodic checkpoint in $src"
if [ "$mpi_built" = "ON" ]; then
  mpi 3 "$bin" run "$scen" -o "$tmp/r3" "${sets[@]}" "${ck[@]}" --restart "$first" > "$tmp/r3.log" 2>&1 || bad "restart on 3 ranks"
  same "$tmp/r3" "2 ranks' $(basename "$first") restarted on 3 ranks"
  mpi 4 "$bin" run "$scen" -o "$tmp/f4" "${sets[@]}" --restart "$tmp/np2/flow_end.ckpt" > "$tmp/f4.log" 2>&1 ||
    bad "flow-end restart on 4 ranks"
  same "$tmp/f4" "2 ranks' flow_end.ckpt restarted on 4 ranks"
fi
"$bin" run "$scen" -o "$tmp/r1" "${sets[@]}" "${ck[@]}" --decompose --restart "$first" > "$tmp/r1.log" 2>&1 || bad "restart in one process"
same "$tmp/r1" "$src's $(basename "$first") restarted in one process"

# 3. the run of one world reads it (its automatic grid: other bits, the same scene)
"$bin" run "$scen" -o "$tmp/plain" "${sets[@]}" "${ck[@]}" --restart "$first" > "$tmp/plain.log" 2>&1 ||
  bad "the one-world run cannot restart from a decomposed checkpoint"

[ "$fail" -eq 0 ] && echo "ok: the same bits and outputs on 1 process and ${ranks[*]:-no} ranks, and after restarts"
exit $((fail > 0))
