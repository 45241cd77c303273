#!/usr/bin/env bash
# Restart at any time (issue 52): periodic checkpoints, kills, full disks, output directories.
# On the reduced flume, shortened (dam at 0.5 m, 0.25 s packing and capture: ~1 s a run):
#  1. periodic checkpoints change no bit (the same state hash with and without them);
#  2. kill loop: the run is killed with SIGKILL at seeded simulated instants in packing, flow
#     and capture, and restarted each time from its newest checkpoint, into its own directory;
#     the end equals the uninterrupted run: state hash, series.csv, pipes.csv, events.csv,
#     trajectories.csv, series.pvd, the final snapshot, and the summary but for its wall times;
#  3. what a kill -9 leaves (a series.csv cut mid-line, atomic writers' temporary files, the old
#     summary.json) is cleaned by the restart into the same directory;
#  4. full disk (a 400 KiB tmpfs, as root; skipped otherwise): a clear error, exit 1, no
#     half-written summary, and the last good checkpoint restarts to the uninterrupted hash;
#  5. a run owns its output directory: another run's is refused (exit 2, nothing touched)
#     unless --overwrite, which clears the old run's files;
#  6. materials (examples/flume_materials.yaml): a checkpoint keeps the ids and the pairs'
#     springs, and the restart ends on the uninterrupted hash; a scenario that declares other
#     materials is refused, naming the checkpoint's.
set -u
bin="$1"
src_dir="$(cd "$(dirname "$0")/.." && pwd)"
tmp=$(mktemp -d)
mnt=""
bg=""
cleanup() {
  [ -n "$bg" ] && kill -KILL "$bg" 2>/dev/null
  [ -n "$mnt" ] && umount "$mnt" 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT
fail=0
pass=0
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL $*"; fail=$((fail + 1)); }
scen="$src_dir/examples/flume_small.yaml"
sets=(--set flume.x_dam=0.5 --set flume.x_end=0.6 --set phases.packing_time=0.25 --set phases.capture_limit=0.25
      --set output.png=false --set output.vtk=true --set output.snapshot_interval=0.2
      --set "output.trajectory_ids=[0, 7, 100]" --set output.trajectory_interval=0.005 --threads 1)
hash() { /usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['state_hash'])" "$1" 2>/dev/null; }
# the summary without what depends on the wall clock or on the restart itself
summary_core() {
  /usr/bin/python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
for k in ('wall_time_s', 'phase_wall_s', 'timers_s', 'front_prefetch', 'restarted_from', 'restart_flow_wall_s'):
    d.pop(k, None)
print(json.dumps(d, sort_keys=True))" "$1"
}
newest() { ls "$1"/checkpoint_*.ckpt 2>/dev/null | sort | tail -n 1; }
export SD_PREFETCH=off # (the same bits either way; the summary then names no timing trial)

# 1. the uninterrupted run, with and without periodic checkpoints
"$bin" run "$scen" -o "$tmp/ref" "${sets[@]}" --set output.checkpoint_interval=0.05 > "$tmp/ref.log" 2>&1
c1=$?
"$bin" run "$scen" -o "$tmp/plain" "${sets[@]}" > "$tmp/plain.log" 2>&1
c2=$?
ref=$(hash "$tmp/ref/summary.json")
nck=$(ls "$tmp/ref"/checkpoint_*.ckpt 2>/dev/null | wc -l)
echo "uninterrupted: hash $ref; without checkpoints $(hash "$tmp/plain/summary.json"); $nck checkpoints kept"
if [ "$c1" -eq 0 ] && [ "$c2" -eq 0 ] && [ -n "$ref" ] && [ "$ref" = "$(hash "$tmp/plain/summary.json")" ] \
   && [ "$nck" -eq 2 ] && cmp -s "$tmp/ref/series.csv" "$tmp/plain/series.csv"; then ok
else bad "checkpoints changed the run (exit $c1/$c2, $nck kept)"; cat "$tmp/ref.log"; fi

# 2. kill loop: SIGKILL once the run's log shows it past each seeded instant (one in packing,
#    two in flow, two in capture), then restart from the newest checkpoint
RANDOM=52
windows=("0.07 0.18" "0.32 0.42" "0.50 0.60" "0.72 0.80" "0.84 0.90")
run_dir="$tmp/kill"
phases=""
kills=0
for w in "${windows[@]}"; do
  set -- $w
  r=$RANDOM
  t_kill=$(/usr/bin/python3 -c "print(f'{$1 + ($2 - $1) * $r / 32767:.3f}')")
  ck=$(newest "$run_dir")
  if [ -n "$ck" ]; then args=(--restart "$ck"); else args=(--overwrite); fi
  "$bin" run "$scen" -o "$run_dir" --progress 0 "${sets[@]}" --set output.checkpoint_interval=0.05 "${args[@]}" \
    > "$tmp/kill$kills.log" 2>&1 &
  bg=$!
  for _ in $(seq 3000); do
    t=$(grep -o '^phase=[a-z]* t=[0-9.]*' "$tmp/kill$kills.log" 2>/dev/null | tail -n 1 | sed 's/.*t=//')
    [ -n "$t" ] && /usr/bin/python3 -c "import sys; sys.exit(not $t >= $t_kill)" && break
    kill -0 "$bg" 2>/dev/null || break
    sleep 0.01
  done
  kill -KILL "$bg" 2>/dev/null
  wait "$bg" 2>/dev/null
  bg=""
  p=$(grep -o 'phase [a-z]*$' "$tmp/kill$kills.log" | head -n 1 | sed 's/phase //')
  [ -n "$p" ] && phases="$phases $p"
  echo "kill $kills at t >= $t_kill s (restarted from: ${ck:-the start}${p:+, phase $p})"
  kills=$((kills + 1))
done
ck=$(newest "$run_dir")
"$bin" run "$scen" -o "$run_dir" "${sets[@]}" --set output.checkpoint_interval=0.05 --restart "$ck" > "$tmp/last.log" 2>&1
code=$?
p=$(grep -o 'phase [a-z]*$' "$tmp/last.log" | head -n 1 | sed 's/phase //')
phases="$phases $p"
echo "after $kills kills: exit $code, hash $(hash "$run_dir/summary.json"); restarts in:$phases"
if [ "$code" -eq 0 ] && [ "$(hash "$run_dir/summary.json")" = "$ref" ]; then ok; else bad "kill loop: exit $code"; cat "$tmp/last.log"; fi
for p in packing flow capture; do
  case " $phases " in *" $p "*) ok ;; *) bad "no restart from a checkpoint in the $p phase ($phases)" ;; esac
done
[ "$(wc -l < "$tmp/ref/events.csv")" -gt 1 ] && ok || bad "the uninterrupted run has no impact event in events.csv"
for f in series.csv pipes.csv events.csv trajectories.csv series.pvd spheres_final.vtp cylinders_final.vtp spheres_000003.vtp cylinders_000006.vtp; do
  cmp -s "$tmp/ref/$f" "$run_dir/$f" && ok || bad "kill loop: $f differs from the uninterrupted run's"
done
[ "$(summary_core "$tmp/ref/summary.json")" = "$(summary_core "$run_dir/summary.json")" ] && ok \
  || { bad "kill loop: summary differs"; diff <(summary_core "$tmp/ref/summary.json") <(summary_core "$run_dir/summary.json"); }

# 3. what a kill -9 leaves behind, made by hand: a row cut mid-line, the atomic writers'
#    temporary files (summary, VTK, checkpoint, a copy) and the old run's summary.json
cp -r "$tmp/ref" "$tmp/left"
ck=$(ls "$tmp/left"/checkpoint_*.ckpt | sort | head -n 1)
printf '0.912345,capt' >> "$tmp/left/series.csv"
for f in summary.json.tmp spheres_000004.vtp.a1B2c3 series.pvd.Zz9Yy8 checkpoint_0000099999.ckpt.tmp.QqWwEe series.csv.tmp; do
  echo junk > "$tmp/left/$f"
done
"$bin" run "$scen" -o "$tmp/left" "${sets[@]}" --set output.checkpoint_interval=0.05 --restart "$ck" > "$tmp/left.log" 2>&1
code=$?
left=$(ls "$tmp/left" | grep -E '\.tmp|\.[A-Za-z0-9]{6}$' | tr '\n' ' ')
if [ "$code" -eq 0 ] && [ -z "$left" ] && cmp -s "$tmp/ref/series.csv" "$tmp/left/series.csv" \
   && [ "$(hash "$tmp/left/summary.json")" = "$ref" ]; then ok
else bad "restart after a kill's leftovers: exit $code, left: $left"; cat "$tmp/left.log"; fi

# 4. full disk: a 400 KiB file system holds one or two checkpoints (~200 KiB each), not three
if [ "$(id -u)" -ne 0 ]; then
  echo "SKIP full disk: mounting a tmpfs needs root (CI runs as root)"
elif ! mkdir -p "$tmp/small" || ! mount -t tmpfs -o size=400k tmpfs "$tmp/small" 2>"$tmp/mount.err"; then
  echo "SKIP full disk: cannot mount a tmpfs here: $(cat "$tmp/mount.err")"
else
  mnt="$tmp/small"
  "$bin" run "$scen" -o "$mnt/run" "${sets[@]}" --set output.vtk=false --set output.checkpoint_interval=0.05 \
    > "$tmp/full.log" 2>&1
  code=$?
  echo "full disk: exit $code: $(grep -m1 'cannot write' "$tmp/full.log")"
  if [ "$code" -eq 1 ] && grep -q "cannot write: .*No space left on device" "$tmp/full.log"; then ok
  else bad "full disk: exit $code"; cat "$tmp/full.log"; fi
  # no half-written summary: none, or a whole one that says the run failed; no temporary file
  if [ -e "$mnt/run/summary.json" ]; then
    /usr/bin/python3 -c "import json,sys; sys.exit(json.load(open(sys.argv[1]))['exit_code'] != 1)" "$mnt/run/summary.json" \
      && ok || bad "full disk: summary.json is not a whole one saying exit 1"
  else ok; fi
  [ -z "$(ls "$mnt/run" | grep -E '\.tmp|\.[A-Za-z0-9]{6}$')" ] && ok || bad "full disk: temporary files left: $(ls "$mnt/run")"
  # the last good checkpoint is intact: restarted elsewhere (with the time series), it finishes
  # with the uninterrupted run's hash
  ck=$(newest "$mnt/run")
  mkdir "$tmp/after_full" && cp "$ck" "$mnt/run/series.csv" "$mnt/run/trajectories.csv" "$tmp/after_full/" 2>/dev/null
  "$bin" run "$scen" -o "$tmp/after_full" "${sets[@]}" --set output.vtk=false --restart "$tmp/after_full/$(basename "$ck")" \
    > "$tmp/after_full.log" 2>&1
  code=$?
  echo "restart from ${ck##*/} after the full disk: exit $code, hash $(hash "$tmp/after_full/summary.json")"
  [ -n "$ck" ] && [ "$code" -eq 0 ] && [ "$(hash "$tmp/after_full/summary.json")" = "$ref" ] && ok \
    || { bad "full disk: the last checkpoint does not restart to the reference"; cat "$tmp/after_full.log"; }
  umount "$mnt" && mnt=""
fi

# 5. the output directory is the run's: another run's is refused, untouched ...
before=$(ls -l --time-style=+%s.%N "$tmp/plain" | md5sum)
"$bin" run "$scen" -o "$tmp/plain" "${sets[@]}" > "$tmp/own.log" 2>&1
code=$?
if [ "$code" -eq 2 ] && grep -q "plain: the output directory is not empty (it holds another run's files" "$tmp/own.log" \
   && grep -q -- "--overwrite" "$tmp/own.log" && [ "$before" = "$(ls -l --time-style=+%s.%N "$tmp/plain" | md5sum)" ]; then ok
else bad "reused directory: exit $code"; cat "$tmp/own.log"; fi
# ... and --overwrite clears the old run's files (here: its snapshots, which this run does not
# write) but keeps a stranger's
echo "notes" > "$tmp/plain/notes.txt"
"$bin" run "$scen" -o "$tmp/plain" "${sets[@]}" --set output.snapshot_interval=0 --overwrite > "$tmp/over.log" 2>&1
code=$?
if [ "$code" -eq 0 ] && [ ! -e "$tmp/plain/spheres_000003.vtp" ] && [ -e "$tmp/plain/notes.txt" ] \
   && ! grep -q '000003' "$tmp/plain/series.pvd" && [ "$(hash "$tmp/plain/summary.json")" = "$ref" ]; then ok
else bad "--overwrite: exit $code"; cat "$tmp/over.log"; ls "$tmp/plain"; fi
# a directory holding other files only is refused too (nothing deleted)
mkdir "$tmp/other" && echo x > "$tmp/other/data.txt"
"$bin" run "$scen" -o "$tmp/other" "${sets[@]}" > "$tmp/other.log" 2>&1
[ $? -eq 2 ] && grep -q "holds other files: data.txt" "$tmp/other.log" && [ -e "$tmp/other/data.txt" ] && ok \
  || { bad "a directory of other files"; cat "$tmp/other.log"; }
# a periodic checkpoint continues only its own scenario
"$bin" run "$scen" -o "$tmp/wrong" "${sets[@]}" --set dam.l_v=0.03 --restart "$(newest "$tmp/ref")" > "$tmp/wrong.log" 2>&1
[ $? -eq 2 ] && grep -q "only solver.threads and output.checkpoint_interval may differ" "$tmp/wrong.log" && [ ! -e "$tmp/wrong" ] \
  && ok || { bad "periodic checkpoint with another scenario"; cat "$tmp/wrong.log"; }

# 6. materials: the restart from the older periodic checkpoint ends where the run did
ms="$src_dir/examples/flume_materials.yaml"
"$bin" run "$ms" -o "$tmp/mref" "${sets[@]}" --set output.checkpoint_interval=0.05 > "$tmp/mref.log" 2>&1
code=$?
mref=$(hash "$tmp/mref/summary.json")
ck=$(ls "$tmp/mref"/checkpoint_*.ckpt 2>/dev/null | sort | head -n 1)
"$bin" run "$ms" -o "$tmp/mres" "${sets[@]}" --restart "$ck" > "$tmp/mres.log" 2>&1
code2=$?
echo "materials: hash $mref, restarted from $(basename "$ck"): $(hash "$tmp/mres/summary.json")"
if [ "$code" -eq 0 ] && [ "$code2" -eq 0 ] && [ -n "$mref" ] && [ "$mref" != "$ref" ] \
   && [ "$(hash "$tmp/mres/summary.json")" = "$mref" ]; then ok
else bad "materials restart: exit $code/$code2"; cat "$tmp/mref.log" "$tmp/mres.log"; fi
# the summary lists the materials, what uses each, and each pair's springs
/usr/bin/python3 - "$tmp/mref/summary.json" <<'PY' && ok || bad "materials in summary.json"
import json, sys
d = json.load(open(sys.argv[1]))
names = [m["name"] for m in d["materials"]]
pairs = {tuple(p["pair"]): p for p in d["contact_pairs"]}
rs, rr = pairs[("rock", "steel")], pairs[("rock", "rock")]
assert names == ["default", "rock", "wood", "steel", "concrete"], names
assert d["materials"][3]["used_by"] == ["dam", "gate"], d["materials"][3]
assert (rs["k_n"], rs["k_s"], rs["tan_phi"], rs["damping"], rs["from"]) == (2e4, 8e3, 0.3, 0.2, "contact_pairs"), rs
assert (rr["k_n"], rr["tan_phi"], rr["from"], rr["can_meet"]) == (1e4, 0.404, "contact", True), rr
assert d["parameters"]["dam.material"] == "steel" and d["parameters"]["spheres.materials"] == ["rock"]
PY
sed 's/^materials: \[rock, wood, steel, concrete\]/materials: [rock, wood, steel, concrete, mud]/' "$ms" > "$tmp/mud.yaml"
"$bin" run "$tmp/mud.yaml" -o "$tmp/mud" "${sets[@]}" --restart "$ck" > "$tmp/mud.log" 2>&1
[ $? -eq 2 ] && grep -q "holds the materials (default, rock, wood, steel, concrete); .*mud.yaml declares others" "$tmp/mud.log" \
  && [ ! -e "$tmp/mud" ] && ok || { bad "a checkpoint with other materials"; cat "$tmp/mud.log"; }

echo "restart: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
