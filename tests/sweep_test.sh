#!/usr/bin/env bash
# `sabodem sweep` with branching, on a 2 x 2 matrix (dam.l_v x logs.count) x 2 seeds of the
# reduced flume with short phases: the dry run lists 4 shared flows and 8 runs; a sweep stopped
# with Ctrl-C after its first runs and resumed runs only what was missing (counted from its
# "started" lines); results.csv, cases.csv and the figures appear; after deleting some results
# and checkpoints a resume recomputes exactly those (a checkpoint whose runs are all done is
# not recomputed) and gives the same bits; a damaged flow checkpoint is refused, naming the
# file, before anything runs; a branched sweep equals a straight (--no-branch) one for one case.
set -u
bin="$1"
src_dir="$(cd "$(dirname "$0")/.." && pwd)"
tmp=$(mktemp -d)
bg=""
trap '[ -n "$bg" ] && kill "$bg" 2>/dev/null; rm -rf "$tmp"' EXIT
fail=0
pass=0
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL $*"; fail=$((fail + 1)); }
started() { grep -c "$1 .* started" "$2"; } # flow|run, log
# results.csv without the columns that depend on the wall clock or on how a run was computed
# (passed elements counted, wall times, branched or not); by column name
bits() {
  /usr/bin/python3 -c 'import csv, sys
skip = ("n_passed", "passed", "wall_s", "flow_wall_s", "branched", "capture_limit_s")
for r in csv.DictReader(open(sys.argv[1])):
    print(",".join(v for k, v in r.items() if k not in skip))' "$1"
}
col() { # file, column, then awk-style filters as column=value ...: the column's values
  /usr/bin/python3 -c 'import csv, sys
f, c, conds = sys.argv[1], sys.argv[2], [a.split("=", 1) for a in sys.argv[3:]]
for i, r in enumerate(csv.DictReader(open(f))):
    if all((r[k] if k != "#" else str(i + 1)) == v for k, v in conds):
        print(r[c])' "$@"
}

out="$tmp/out"
cat > "$tmp/small.yaml" <<EOF
# a 2 x 2 matrix x 2 seeds of the reduced flume, short phases
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
EOF

# dry run: the plan, nothing written
"$bin" sweep "$tmp/small.yaml" -o "$out" --dry-run > "$tmp/dry.log" 2>&1
code=$?
if [ "$code" -eq 0 ] && grep -q "4 shared flows" "$tmp/dry.log" && [ "$(grep -c '^run case' "$tmp/dry.log")" -eq 8 ] \
   && [ "$(grep -c '^branch ' "$tmp/dry.log")" -eq 4 ] && [ ! -e "$out" ]; then ok; else bad "dry run (exit $code)"; cat "$tmp/dry.log"; fi

# a sweep stopped (SIGINT) once its first runs are done ...
"$bin" sweep "$tmp/small.yaml" -o "$out" --parallel 2 > "$tmp/first.log" 2>&1 &
bg=$!
for _ in $(seq 1 3000); do
  [ "$(ls "$out"/runs/*/result.csv 2>/dev/null | wc -l)" -ge 1 ] && break
  kill -0 "$bg" 2>/dev/null || break
  sleep 0.1
done
kill -INT "$bg" 2>/dev/null
wait "$bg"
code=$?
bg=""
done1=$(ls "$out"/runs/*/result.csv 2>/dev/null | wc -l)
ck1=$(ls "$out"/branch/*/flow_end.ckpt 2>/dev/null | wc -l)
echo "interrupted sweep: exit $code, $done1 runs and $ck1 flow checkpoints done"
if [ "$code" -eq 130 ] && [ "$done1" -ge 1 ] && [ "$done1" -lt 8 ] && [ "$ck1" -ge 1 ]; then ok; else bad "interrupt (exit $code, $done1 done)"; cat "$tmp/first.log"; fi

# ... and resumed: only the missing flows and runs
"$bin" sweep "$tmp/small.yaml" -o "$out" --parallel 2 > "$tmp/resume.log" 2>&1
code=$?
nf=$(started flow "$tmp/resume.log")
nr=$(started run "$tmp/resume.log")
echo "resume: exit $code, $nf flows and $nr runs started"
if [ "$code" -eq 0 ] && [ "$nf" -eq $((4 - ck1)) ] && [ "$nr" -eq $((8 - done1)) ]; then ok; else bad "resume ran $nf flows, $nr runs"; cat "$tmp/resume.log"; fi
grep "branching saved" "$tmp/resume.log" && ok || bad "no 'branching saved' line"
[ "$(wc -l < "$out/results.csv")" -eq 9 ] && [ -s "$out/cases.csv" ] && [ "$(wc -l < "$out/cases.csv")" -eq 5 ] && ok \
  || { bad "results.csv / cases.csv"; cat "$out/results.csv" "$out/plot.log"; }
if /usr/bin/python3 -c "import matplotlib" 2>/dev/null; then
  for f in fig16_pv_vs_kw.png fig17_pv_vs_lv.png heatmap_pv.png; do
    [ -s "$out/$f" ] && ok || { bad "figure $f missing"; cat "$out/plot.log"; }
  done
else
  echo "note: /usr/bin/python3 has no matplotlib: figures not checked"
fi
# every run of a group continued from the same flow: same flow time recorded
cp "$out/results.csv" "$tmp/results1.csv"

# delete some results and checkpoints: a group with runs to redo recomputes its flow; a group
# whose runs are all done does not
rm "$out/runs/case000_seed1/result.csv" "$out/runs/case002_seed1/result.csv" "$out/runs/case001_seed2/result.csv"
rm "$out/branch/logs.count=0_seed1/flow_end.ckpt" "$out/branch/logs.count=4_seed1/flow_end.ckpt"
"$bin" sweep "$tmp/small.yaml" -o "$out" --parallel 2 > "$tmp/resume2.log" 2>&1
code=$?
nf=$(started flow "$tmp/resume2.log")
nr=$(started run "$tmp/resume2.log")
echo "resume after deletions: exit $code, $nf flows and $nr runs started"
if [ "$code" -eq 0 ] && [ "$nf" -eq 1 ] && [ "$nr" -eq 3 ] && grep -q "flow logs.count=0_seed1 started" "$tmp/resume2.log" \
   && [ ! -e "$out/branch/logs.count=4_seed1/flow_end.ckpt" ]; then ok; else bad "partial resume"; cat "$tmp/resume2.log"; fi
# the debris account per run: held + channel + passed volumes positive and P_V = (held +
# channel) / all; the capture's end named; a header per size class (3 here) and no more
if /usr/bin/python3 - "$out/results.csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
cols = list(rows[0].keys())
assert [c for c in cols if c.startswith("p_v_class")] == ["p_v_class0", "p_v_class1", "p_v_class2"], cols
for r in rows:
    h, c, p = float(r["v_held_m3"]), float(r["v_channel_m3"]), float(r["v_passed_m3"])
    assert h >= 0 and c >= 0 and p >= 0 and abs((h + c) / (h + c + p) - float(r["p_v"])) <= 2e-5, r
    assert r["capture_end"] in ("settled", "limit"), r
    # each run's own K_w and l_V/d_max, by hand: 4 logs of 10 x 100 mm (31.416 mL) beside
    # 20/40/120 spheres of 20/15/10 mm (217.29 mL): 12.6315 %; 40 mm / 20 mm, and without the
    # intermediate beam the top beam's 118 mm / 20 mm
    kw = 0.0 if r["logs.count"] == "0" else 31.4159e-6 / (31.4159e-6 + 217.2935e-6)
    assert abs(float(r["k_w"]) - kw) <= 2e-6, (r["k_w"], kw)
    assert float(r["l_v_d_max"]) == (2.0 if r["dam.l_v"] == "0.040" else 5.9), r["l_v_d_max"]
PY
then ok; else bad "results.csv debris columns"; fi
# the recomputed runs carry the same bits (trap ratio and state hash)
if diff <(bits "$tmp/results1.csv") <(bits "$out/results.csv") >/dev/null; then ok
else bad "recomputed results differ"; diff "$tmp/results1.csv" "$out/results.csv"; fi

# a damaged flow checkpoint is refused before anything runs, naming the file
rm "$out/runs/case003_seed2/result.csv"
ck="$out/branch/logs.count=4_seed2/flow_end.ckpt"
/usr/bin/python3 -c "
import sys; p = sys.argv[1]; b = bytearray(open(p, 'rb').read()); b[len(b) // 2] ^= 0x40; open(p, 'wb').write(b)" "$ck"
"$bin" sweep "$tmp/small.yaml" -o "$out" --parallel 2 > "$tmp/corrupt.log" 2>&1
code=$?
if [ "$code" -eq 2 ] && grep -qF "$ck: checksum mismatch" "$tmp/corrupt.log" && ! grep -q "started" "$tmp/corrupt.log"; then ok
else bad "damaged checkpoint (exit $code)"; cat "$tmp/corrupt.log"; fi
# deleting it, as the message says, recomputes that flow
rm "$ck"
"$bin" sweep "$tmp/small.yaml" -o "$out" --parallel 2 > "$tmp/resume3.log" 2>&1
code=$?
if [ "$code" -eq 0 ] && [ "$(started flow "$tmp/resume3.log")" -eq 1 ] && [ "$(started run "$tmp/resume3.log")" -eq 1 ] \
   && diff <(bits "$tmp/results1.csv") <(bits "$out/results.csv") >/dev/null; then ok
else bad "recompute after deleting the damaged checkpoint"; cat "$tmp/resume3.log"; fi

# branched = straight: one case (l_V = 0, 4 logs, seed 1) run without branching
sed -e 's/dam.l_v: \[0.040, 0\]/dam.l_v: [0]/' -e 's/logs.count: \[0, 4\]/logs.count: [4]/' -e 's/runs: 2/runs: 1/' \
  "$tmp/small.yaml" > "$tmp/one.yaml"
"$bin" sweep "$tmp/one.yaml" -o "$tmp/one" --no-branch > "$tmp/one.log" 2>&1
code=$?
a="$(col "$out/results.csv" p_v dam.l_v=0 logs.count=4 seed=1) $(col "$out/results.csv" state_hash dam.l_v=0 logs.count=4 seed=1)"
b="$(col "$tmp/one/results.csv" p_v '#=1') $(col "$tmp/one/results.csv" state_hash '#=1')"
echo "branched: $a; straight: $b"
if [ "$code" -eq 0 ] && [ -n "$a" ] && [ "$a" = "$b" ] && [ ! -e "$tmp/one/branch" ]; then ok; else bad "branched run differs from the straight one"; cat "$tmp/one.log"; fi

# bad command lines
"$bin" sweep "$tmp/small.yaml" --parallel zero > "$tmp/bad.log" 2>&1
[ $? -eq 2 ] && grep -q "parallel" "$tmp/bad.log" && ok || bad "--parallel zero accepted"

# a sweep killed outright (SIGKILL: no handler runs) takes its running children with it
sed 's/phases.packing_time: 0.25/phases.packing_time: 60/' "$tmp/small.yaml" > "$tmp/long.yaml" # (children that live)
"$bin" sweep "$tmp/long.yaml" -o "$tmp/killed" --parallel 2 > "$tmp/killed.log" 2>&1 &
kp=$!
for _ in $(seq 300); do grep -q "started" "$tmp/killed.log" 2>/dev/null && break; sleep 0.1; done
children=$(pgrep -P "$kp" | tr '\n' ' ')
kill -KILL "$kp"
wait "$kp" 2>/dev/null
left=""
for _ in $(seq 30); do
  left=""
  for c in $children; do kill -0 "$c" 2>/dev/null && left="$left $c"; done
  [ -z "$left" ] && break
  sleep 0.1
done
[ -n "$children" ] && [ -z "$left" ] && ok || bad "killed sweep: children '$children' left running:$left"
for c in $left; do kill -KILL "$c" 2>/dev/null; done

echo "sweep: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
