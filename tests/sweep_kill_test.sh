#!/usr/bin/env bash
# Sweeps that survive (issue 52): a tiny branched sweep (dam.l_v x 2 seeds of the shortened
# reduced flume: 4 runs from 2 shared flows, checkpoints every 0.02 s) is killed with SIGKILL at
# seeded instants and resumed at once, six times (the flows and runs killed on the way continue
# from their checkpoints), then resumed to the end: results.csv has exactly one row per run,
# with the values of an uninterrupted sweep (trap ratios, forces, state hashes); no child is
# left running. A run that crashes (its process killed by a signal) is reported as failed, with
# its log and how it ended, and the sweep exits 1.
set -u
bin="$1"
src_dir="$(cd "$(dirname "$0")/.." && pwd)"
tmp=$(mktemp -d)
bg=""
trap '[ -n "$bg" ] && kill -KILL "$bg" 2>/dev/null; rm -rf "$tmp"' EXIT
fail=0
pass=0
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL $*"; fail=$((fail + 1)); }
cat > "$tmp/tiny.yaml" <<EOF
base: $src_dir/examples/flume_small.yaml
runs: 2
vary:
  dam.l_v: [0.040, 0]
set:
  output.png: false
  output.vtk: false
  flume.x_dam: 0.5
  flume.x_end: 0.6
  phases.packing_time: 0.25
  phases.capture_limit: 0.25
  output.checkpoint_interval: 0.02
EOF
# the columns that do not depend on the wall clock: all but wall_s and flow_wall_s
values() {
  /usr/bin/python3 -c 'import csv, sys
for r in csv.DictReader(open(sys.argv[1])):
    print(",".join(v for k, v in r.items() if k not in ("wall_s", "flow_wall_s")))' "$1"
}
descendants() { # every process below $1
  local c
  for c in $(pgrep -P "$1"); do echo "$c"; descendants "$c"; done
}

"$bin" sweep "$tmp/tiny.yaml" -o "$tmp/ref" --parallel 2 > "$tmp/ref.log" 2>&1
code=$?
[ "$code" -eq 0 ] && [ "$(wc -l < "$tmp/ref/results.csv")" -eq 5 ] && ok || { bad "uninterrupted sweep: exit $code"; cat "$tmp/ref.log"; }

# six kills, each a seeded 0.3-1.5 s after the sweep (re)started, resumed at once each time
RANDOM=4052
prev=0
seen=""
for k in 1 2 3 4 5 6; do
  ms=$((300 + RANDOM % 1200))
  delay=$(printf '%d.%03d' $((ms / 1000)) $((ms % 1000)))
  "$bin" sweep "$tmp/tiny.yaml" -o "$tmp/k" --parallel 2 > "$tmp/k$k.log" 2>&1 &
  bg=$!
  sleep "$delay"
  kids=$(descendants "$bg" | tr '\n' ' ')
  kill -KILL "$bg" 2>/dev/null
  wait "$bg" 2>/dev/null
  bg=""
  seen="$seen $kids"
  done_now=$(ls "$tmp"/k/runs/*/result.csv 2>/dev/null | wc -l)
  echo "kill $k after $delay s: $done_now of 4 runs done"
  [ "$done_now" -ge "$prev" ] || bad "kill $k: finished runs went from $prev to $done_now"
  prev=$done_now
done
"$bin" sweep "$tmp/tiny.yaml" -o "$tmp/k" --parallel 2 > "$tmp/last.log" 2>&1
code=$?
rows=$(($(wc -l < "$tmp/k/results.csv") - 1))
echo "resumed to the end: exit $code, $rows rows"
if [ "$code" -eq 0 ] && [ "$rows" -eq 4 ] && diff <(values "$tmp/ref/results.csv") <(values "$tmp/k/results.csv") >/dev/null; then ok
else bad "killed and resumed sweep differs (exit $code)"; diff <(values "$tmp/ref/results.csv") <(values "$tmp/k/results.csv"); cat "$tmp/last.log"; fi
# exactly one row per run: every case/seed pair once
[ "$(cut -d, -f1,2 "$tmp/k/results.csv" | sort | uniq -d | wc -l)" -eq 0 ] && ok || bad "a run has two rows"
# the killed sweeps' children all stopped
left=""
for _ in $(seq 50); do
  left=""
  for c in $seen; do kill -0 "$c" 2>/dev/null && left="$left $c"; done
  [ -z "$left" ] && break
  sleep 0.1
done
[ -z "$left" ] && ok || bad "children of killed sweeps still running:$left"

# a crashed run: its process killed outright (as a segfault or the OOM killer would) once it
# has started; reported with how it ended and its log, and the sweep exits 1
sed -e 's/phases.packing_time: 0.25/phases.packing_time: 60/' -e 's/dam.l_v: \[0.040, 0\]/dam.l_v: [0.040]/' \
  -e 's/runs: 2/runs: 1/' "$tmp/tiny.yaml" > "$tmp/crash.yaml" # (one run, that lives)
"$bin" sweep "$tmp/crash.yaml" -o "$tmp/crash" --parallel 1 > "$tmp/crash.log" 2>&1 &
bg=$!
victim=""
for _ in $(seq 600); do
  if grep -q "run case000_seed1 started" "$tmp/crash.log" 2>/dev/null; then victim=$(pgrep -P "$bg" | head -n 1); [ -n "$victim" ] && break; fi
  sleep 0.05
done
[ -n "$victim" ] && kill -KILL "$victim"
wait "$bg"
code=$?
bg=""
if [ -n "$victim" ] && [ "$code" -eq 1 ] \
   && grep -q "sweep: run .*/runs/case000_seed1 failed (killed by signal 9, Killed; see .*/runs/case000_seed1.log)" "$tmp/crash.log" \
   && grep -q "1 run(s) failed" "$tmp/crash.log" && grep -q "case000_seed1: see .*/runs/case000_seed1.log" "$tmp/crash.log" \
   && [ "$(wc -l < "$tmp/crash/results.csv")" -eq 1 ]; then ok
else bad "crashed run not reported (exit $code)"; cat "$tmp/crash.log"; fi

echo "sweep_kill: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
