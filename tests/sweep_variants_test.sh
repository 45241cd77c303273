#!/usr/bin/env bash
# Sweeps over layouts and gradings, their time estimate, and the identity of shared flows
# (docs/sweep.md), on the reduced flume with short phases:
# - the dry run's time estimate: each run's equals what `sabodem check` prints for its case; the
#   straight total is their sum, the branched total that less (runs - 1) x the shared packing and
#   flow of each group, exactly (whole milliseconds); with one process the elapsed time is the work
#   left, with a process per task the longest flow and its longest capture;
# - named variants (layout: narrow / wide, two keys each) x a list-valued key (spheres.counts):
#   two shared flows, one per grading, each branched into the two layouts; results.csv carries the
#   variant names and the lists, and its trap ratios and state hashes equal those of the four
#   scenarios run one by one with `sabodem run`; cases.csv, the heatmap and Fig. 16's lines are
#   labelled with them (variants in the sweep file's order);
#   a variant that also sets a key acting before the flow end gets a flow of its own;
# - a flow checkpoint is reused only when its identity matches: after its stored engine identity is
#   edited, or a key acting before the flow end (logs.count) is edited in the sweep file, or its
#   identity file is gone, the resumed sweep says so and computes the flow again (the same bits when
#   only the engine record was edited); after editing only a capture key it branches from it;
# - bad variants are refused with file:line:col.
set -u
bin="$1"
src_dir="$(cd "$(dirname "$0")/.." && pwd)"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
pass=0
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL $*"; fail=$((fail + 1)); }
started() { grep -c "$1 .* started" "$2"; } # flow|run, log
short='  output.png: false
  output.vtk: false
  flume.x_dam: 0.5
  flume.x_end: 0.6
  phases.packing_time: 0.25
  phases.capture_limit: 0.25'

# --- the time estimate against `sabodem check`, on a 2 x 2 matrix x 2 seeds
cat > "$tmp/est.yaml" <<EOF
base: $src_dir/examples/flume_small.yaml
runs: 2
vary:
  dam.l_v: [0.040, 0]
  logs.count: [0, 4]
set:
$short
EOF
for p in 1 2 64; do
  "$bin" sweep "$tmp/est.yaml" -o "$tmp/est" --dry-run --parallel $p > "$tmp/est_p$p.log" 2>&1 || bad "estimate dry run --parallel $p"
done
"$bin" sweep "$tmp/est.yaml" -o "$tmp/est" --dry-run --no-branch --parallel 1 > "$tmp/est_nb.log" 2>&1 || bad "estimate dry run --no-branch"
for lv in 0.040 0; do
  for lc in 0 4; do
    "$bin" check "$src_dir/examples/flume_small.yaml" --set output.png=false --set output.vtk=false \
      --set flume.x_dam=0.5 --set flume.x_end=0.6 --set phases.packing_time=0.25 --set phases.capture_limit=0.25 \
      --set dam.l_v=$lv --set logs.count=$lc --seed 1 --threads 1 > "$tmp/check_${lv}_$lc.log" 2>&1 || bad "check l_v=$lv logs=$lc"
  done
done
if /usr/bin/python3 - "$tmp" <<'PY'
import re, sys
d = sys.argv[1]
def ms(text):  # "12.345 s" -> 12345, exactly
    whole, frac = re.fullmatch(r"(\d+)\.(\d{3}) s", text).groups()
    return int(whole) * 1000 + int(frac)
num = r"\d+\.\d{3} s"
check = {}
for lv in ("0.040", "0"):
    for lc in ("0", "4"):
        t = open(f"{d}/check_{lv}_{lc}.log").read()
        m = re.search(rf"time estimate: ({num}) on one core \(packing and flow ({num}), capture ({num})\)", t)
        assert m, t
        run, flow, cap = (ms(x) for x in m.groups())
        assert run == flow + cap, (run, flow, cap)
        check[(lv, lc)] = (run, flow)
def plan(name):
    t = open(f"{d}/{name}").read()
    runs = re.findall(rf"^run (\S+): dam.l_v=(\S+) logs.count=(\S+) solver.seed=(\d+)(?: \(branch (\S+)\))? est ({num})"
                      rf"(?: \(capture ({num})\))?$", t, re.M)
    flows = dict(re.findall(rf"^branch (\S+): pack \+ flow, est ({num}) ->", t, re.M))
    total = {k: ms(v) for k, v in re.findall(rf"^  (straight|branched|left to do|elapsed)[^:]*:\s+({num})", t, re.M)}
    return runs, flows, total
runs, flows, total = plan("est_p1.log")
assert len(runs) == 8 and len(flows) == 4, (runs, flows)
straight = 0
members = {}
for name, lv, lc, seed, branch, est, cap in runs:
    run, flow = check[(lv, lc)]
    assert ms(est) == run, (name, est, run)              # the run's estimate is check's
    assert ms(cap) == run - flow, (name, cap, run, flow)  # its capture, after the shared flow
    assert ms(flows[branch]) == flow, (branch, flows[branch], flow)
    straight += run
    members.setdefault(branch, []).append((run, flow))
assert total["straight"] == straight, (total, straight)
shared = sum((len(m) - 1) * m[0][1] for m in members.values())
assert shared > 0 and total["branched"] == straight - shared, (total, straight, shared)
assert total["left to do"] == total["branched"], total
assert total["elapsed"] == total["left to do"], total  # one process: one task after the other
# a process for every task: each flow at once, then its runs at once
_, _, total64 = plan("est_p64.log")
longest = max(m[0][1] + max(r - f for r, f in m) for m in members.values())
assert total64["elapsed"] == longest, (total64, longest)
_, _, total2 = plan("est_p2.log")
assert total64["elapsed"] < total2["elapsed"] < total["elapsed"], (total64, total2, total)
# without branching: each run on its own, the straight total
runs_nb, flows_nb, total_nb = plan("est_nb.log")
assert not flows_nb and "branched" not in total_nb and total_nb["left to do"] == straight == total_nb["elapsed"], total_nb
print(f"estimate: straight {straight} ms = sum of check's; branched {total['branched']} ms = straight - {shared} ms shared")
PY
then ok; else bad "time estimate"; cat "$tmp/est_p1.log"; fi
# the job array's units carry their estimates too
"$bin" sweep "$tmp/est.yaml" -o "$tmp/est_slurm" --emit slurm > "$tmp/emit.log" 2>&1 || bad "emit slurm"
if [ "$(grep -c $'^[0-9]\tflow .*\t[0-9]*\.[0-9][0-9][0-9] s$' "$tmp/est_slurm/slurm/units.txt")" -eq 4 ] \
   && grep -q "Time estimate on one core" "$tmp/est_slurm/slurm/README"; then ok; else bad "units.txt estimates"; cat "$tmp/est_slurm/slurm/units.txt"; fi

# --- named variants x a list-valued key
cat > "$tmp/v.yaml" <<EOF
base: $src_dir/examples/flume_small.yaml
runs: 1
vary:
  layout:
    narrow: {dam.l_h: 0.030, dam.l_v: 0.040}
    wide:   {dam.l_h: 0.045, dam.l_v: 0}
  spheres.counts: [[20, 40, 120], [10, 50, 110]]
set:
$short
  logs.count: 2
EOF
"$bin" sweep "$tmp/v.yaml" -o "$tmp/v" --dry-run > "$tmp/v_dry.log" 2>&1
if grep -q "^branching on layout: 2 shared flows (packing + flow, once each) for 4 runs" "$tmp/v_dry.log" \
   && grep -q "^branch spheres.counts=20-40-120_seed1: pack + flow, est .* -> case000_seed1 case002_seed1$" "$tmp/v_dry.log" \
   && grep -q "^branch spheres.counts=10-50-110_seed1: pack + flow, est .* -> case001_seed1 case003_seed1$" "$tmp/v_dry.log" \
   && grep -qF "run case003_seed1: layout=wide spheres.counts=[10, 50, 110] solver.seed=1 (branch spheres.counts=10-50-110_seed1)" "$tmp/v_dry.log"
then ok; else bad "variants dry run"; cat "$tmp/v_dry.log"; fi
# a variant that also changes the packing (a density) is not branched: its runs are straight
sed 's/^    wide: .*/&\n    heavy:  {dam.l_h: 0.045, spheres.density: 2100}/' "$tmp/v.yaml" > "$tmp/mixed.yaml"
"$bin" sweep "$tmp/mixed.yaml" -o "$tmp/mixed" --dry-run > "$tmp/mixed_dry.log" 2>&1
if grep -q "^branching on layout: 2 shared flows (packing + flow, once each) for 4 runs" "$tmp/mixed_dry.log" \
   && grep -q "^branch layout=narrow+wide_spheres.counts=20-40-120_seed1: .* -> case000_seed1 case002_seed1$" "$tmp/mixed_dry.log" \
   && grep -qE "^run case004_seed1: layout=heavy spheres.counts=\[20, 40, 120\] solver.seed=1 est [0-9.]+ s$" "$tmp/mixed_dry.log" \
   && grep -qE "^run case005_seed1: layout=heavy .* solver.seed=1 est [0-9.]+ s$" "$tmp/mixed_dry.log"
then ok; else bad "mixed variant dry run"; cat "$tmp/mixed_dry.log"; fi

"$bin" sweep "$tmp/v.yaml" -o "$tmp/v" --parallel 2 > "$tmp/v.log" 2>&1
code=$?
[ "$code" -eq 0 ] && [ "$(started flow "$tmp/v.log")" -eq 2 ] && [ "$(started run "$tmp/v.log")" -eq 4 ] && ok \
  || { bad "variants sweep (exit $code)"; cat "$tmp/v.log"; }
# the four scenarios one by one
i=0
for layout in "dam.l_h=0.030 dam.l_v=0.040" "dam.l_h=0.045 dam.l_v=0"; do
  for counts in "[20, 40, 120]" "[10, 50, 110]"; do
    sets=()
    for kv in $layout; do sets+=(--set "$kv"); done
    "$bin" run "$src_dir/examples/flume_small.yaml" --set output.png=false --set output.vtk=false \
      --set flume.x_dam=0.5 --set flume.x_end=0.6 --set phases.packing_time=0.25 --set phases.capture_limit=0.25 \
      --set logs.count=2 "${sets[@]}" --set "spheres.counts=$counts" --seed 1 --threads 1 -o "$tmp/one$i" \
      > "$tmp/one$i.log" 2>&1 || bad "straight run $i"
    i=$((i + 1))
  done
done
if /usr/bin/python3 - "$tmp" <<'PY'
import csv, json, sys
d = sys.argv[1]
rows = list(csv.DictReader(open(f"{d}/v/results.csv")))
want = [("narrow", "[20, 40, 120]"), ("narrow", "[10, 50, 110]"), ("wide", "[20, 40, 120]"), ("wide", "[10, 50, 110]")]
assert [(r["layout"], r["spheres.counts"]) for r in rows] == want, rows
assert list(rows[0].keys())[2:4] == ["layout", "spheres.counts"], rows[0].keys()
for i, r in enumerate(rows):
    s = json.load(open(f"{d}/one{i}/summary.json"))
    assert r["branched"] == "1", r
    assert r["state_hash"] == s["state_hash"], (i, r["state_hash"], s["state_hash"])
    assert float(r["p_v"]) == round(s["trap_ratio"], 6), (i, r["p_v"], s["trap_ratio"])
    print(f"{r['layout']} {r['spheres.counts']}: P_V {r['p_v']}, state hash {r['state_hash']} (branched = straight)")
cases = list(csv.DictReader(open(f"{d}/v/cases.csv")))
assert [(c["layout"], c["spheres.counts"]) for c in cases] == want, cases
PY
then ok; else bad "variants: branched results differ from the straight runs"; cat "$tmp/v/results.csv"; fi
if /usr/bin/python3 -c "import matplotlib" 2>/dev/null; then
  [ -s "$tmp/v/heatmap_pv.png" ] && ! grep -q Traceback "$tmp/v/plot.log" && ok || { bad "variants heatmap"; cat "$tmp/v/plot.log"; }
fi
# the figures over variants x logs.count (results.csv made up): Fig. 16 with a line per layout
mkdir -p "$tmp/fig"
/usr/bin/python3 - "$tmp/fig/results.csv" <<'PY'
import csv, sys
w = csv.writer(open(sys.argv[1], "w", newline=""))
w.writerow("case,seed,layout,logs.count,p_v,p_v_class0,p_v_logs,k_w,l_v_d_max,v_held_m3,v_channel_m3,v_passed_m3,"
           "capture_end,peak_dam_force_N,passed,wall_s,capture_limit_s,flow_wall_s,branched,state_hash".split(","))
for c, (layout, lv, logs, kw) in enumerate((l, lv, n, k) for l, lv in (("wide", 5.9), ("narrow", 1.5))
                                          for n, k in ((0, 0.0), (32, 0.05))):
    w.writerow([c, 1, layout, logs, 0.5 + 0.1 * c, 0.5, 0.5, kw, lv, 1e-5, 1e-5, 1e-5, "settled", 1, 0, 1, 6, 1, 1, "0"])
PY
if /usr/bin/python3 -c "import matplotlib" 2>/dev/null; then
  /usr/bin/python3 "$src_dir/scripts/plot_sweep.py" "$tmp/fig" > "$tmp/fig.log" 2>&1
  [ -s "$tmp/fig/fig16_pv_vs_kw.png" ] && [ -s "$tmp/fig/heatmap_pv.png" ] \
    && [ "$(cut -d, -f1,2 "$tmp/fig/cases.csv" | tr '\n' ' ')" = "layout,logs.count wide,0 wide,32 narrow,0 narrow,32 " ] \
    && ok || { bad "figures over variants"; cat "$tmp/fig.log" "$tmp/fig/cases.csv"; }
fi
cp "$tmp/v/results.csv" "$tmp/v_results0.csv"
hash_of() { /usr/bin/python3 -c 'import csv, sys
print([r["state_hash"] for r in csv.DictReader(open(sys.argv[1])) if r["case"] == sys.argv[2]][0])' "$1" "$2"; }

# --- a checkpoint of another engine is not reused (its stored identity edited)
ck="$tmp/v/branch/spheres.counts=20-40-120_seed1"
sed -i 's/"engine":\t"sabodem /"engine":\t"sabodem-other /' "$ck/identity.json"
rm "$tmp/v/runs/case000_seed1/result.csv"
"$bin" sweep "$tmp/v.yaml" -o "$tmp/v" --dry-run > "$tmp/id_dry.log" 2>&1
grep -q "^branch spheres.counts=20-40-120_seed1: pack + flow again, est .* (its checkpoint is not reused: made by another engine: sabodem-other" "$tmp/id_dry.log" \
  && grep -q "^branch spheres.counts=10-50-110_seed1: not needed" "$tmp/id_dry.log" && ok || { bad "dry run: stale engine"; cat "$tmp/id_dry.log"; }
"$bin" sweep "$tmp/v.yaml" -o "$tmp/v" --parallel 2 > "$tmp/id_engine.log" 2>&1
code=$?
if [ "$code" -eq 0 ] && grep -q "not branching from $ck/flow_end.ckpt: made by another engine: sabodem-other" "$tmp/id_engine.log" \
   && [ "$(started flow "$tmp/id_engine.log")" -eq 1 ] && [ "$(started run "$tmp/id_engine.log")" -eq 1 ] \
   && ! grep -q "sabodem-other" "$ck/identity.json" \
   && [ "$(hash_of "$tmp/v/results.csv" 0)" = "$(hash_of "$tmp/v_results0.csv" 0)" ]
then ok; else bad "another engine's checkpoint (exit $code)"; cat "$tmp/id_engine.log"; fi

# --- a checkpoint without an identity (an older sweep's, or one stopped before writing it)
rm "$ck/identity.json" "$tmp/v/runs/case002_seed1/result.csv"
"$bin" sweep "$tmp/v.yaml" -o "$tmp/v" --parallel 2 > "$tmp/id_none.log" 2>&1
code=$?
[ "$code" -eq 0 ] && grep -q "not branching from $ck/flow_end.ckpt: no identity" "$tmp/id_none.log" \
  && [ "$(started flow "$tmp/id_none.log")" -eq 1 ] && [ -s "$ck/identity.json" ] \
  && [ "$(hash_of "$tmp/v/results.csv" 2)" = "$(hash_of "$tmp/v_results0.csv" 2)" ] && ok \
  || { bad "checkpoint without identity (exit $code)"; cat "$tmp/id_none.log"; }

# --- a key that acts before the flow end edited: the flow is computed again
sed 's/^  logs.count: 2$/  logs.count: 3/' "$tmp/v.yaml" > "$tmp/v_logs.yaml"
rm "$tmp/v/runs/case001_seed1/result.csv"
"$bin" sweep "$tmp/v_logs.yaml" -o "$tmp/v" --parallel 2 > "$tmp/id_pre.log" 2>&1
code=$?
ck2="$tmp/v/branch/spheres.counts=10-50-110_seed1"
if [ "$code" -eq 0 ] && grep -q "not branching from $ck2/flow_end.ckpt: made for other values of keys that act before the flow end: logs.count 2 -> 3; computing that flow again" "$tmp/id_pre.log" \
   && [ "$(started flow "$tmp/id_pre.log")" -eq 1 ] && [ "$(started run "$tmp/id_pre.log")" -eq 1 ] \
   && grep -q '"logs.count":	3' "$ck2/identity.json" \
   && [ "$(hash_of "$tmp/v/results.csv" 1)" != "$(hash_of "$tmp/v_results0.csv" 1)" ]
then ok; else bad "pre-branch key edited (exit $code)"; cat "$tmp/id_pre.log"; fi

# --- only a capture key edited: the flow is reused
sed 's/^  phases.capture_limit: 0.25$/  phases.capture_limit: 0.2/' "$tmp/v_logs.yaml" > "$tmp/v_capture.yaml"
rm "$tmp/v/runs/case003_seed1/result.csv"
"$bin" sweep "$tmp/v_capture.yaml" -o "$tmp/v" --parallel 2 > "$tmp/id_post.log" 2>&1
code=$?
[ "$code" -eq 0 ] && [ "$(started flow "$tmp/id_post.log")" -eq 0 ] && [ "$(started run "$tmp/id_post.log")" -eq 1 ] \
  && ! grep -q "not branching" "$tmp/id_post.log" && grep -q "1 flow checkpoint(s) reused" "$tmp/id_post.log" \
  && [ "$(/usr/bin/python3 -c 'import csv, sys
print([r["capture_limit_s"] for r in csv.DictReader(open(sys.argv[1])) if r["case"] == "3"][0])' "$tmp/v/results.csv")" = "0.2000" ] && ok \
  || { bad "capture key edited (exit $code)"; cat "$tmp/id_post.log"; }

# --- bad sweep files: file:line:col
expect_bad() { # name, pattern, yaml
  printf '%s\n' "$3" > "$tmp/bad.yaml"
  "$bin" sweep "$tmp/bad.yaml" -o "$tmp/bad-out" --dry-run > "$tmp/bad.log" 2>&1
  local code=$?
  if [ "$code" -eq 2 ] && grep -Eq -- "$2" "$tmp/bad.log" && [ ! -e "$tmp/bad-out" ]; then ok; else bad "$1 (exit $code)"; cat "$tmp/bad.log"; fi
}
base="base: $src_dir/examples/flume_small.yaml"
expect_bad variant-key "bad.yaml:3:3: vary.dam.l_v: a scenario key takes a list of values" \
  "$base
vary:
  dam.l_v: {a: {dam.l_h: 0.03}}"
expect_bad variant-reserved "bad.yaml:3:3: vary.p_v: the name of a results.csv column" \
  "$base
vary:
  p_v: {a: {dam.l_h: 0.03}}"
expect_bad variant-name "bad.yaml:4:5: vary.layout: 'a b': a variant's name is" \
  "$base
vary:
  layout:
    a b: {dam.l_h: 0.03}"
expect_bad variant-not-map "bad.yaml:4:8: vary.layout.a: expected a mapping of at most 16 scenario keys" \
  "$base
vary:
  layout:
    a: [1, 2]"
expect_bad key-twice "bad.yaml:5:13: vary.dam.l_h: dam.l_h is varied by vary.layout too" \
  "$base
vary:
  layout:
    a: {dam.l_h: 0.03}
  dam.l_h: [0.03, 0.04]"
expect_bad variant-unknown-key "bad.yaml:4:9: unknown key 'dam.l_hh' \(did you mean 'dam.l_h'\?\)" \
  "$base
vary:
  layout:
    a: {dam.l_hh: 0.03}"
expect_bad list-value-range "bad.yaml:3:35: spheres.counts: must be in \[0, 1e\+07\]" \
  "$base
vary:
  spheres.counts: [[20, 40, 120], [20, -4, 120]]"
expect_bad set-list "bad.yaml:4:16: dam.columns: must be in \[0, 100\] \(m\)" \
  "$base
vary: {dam.l_v: [0.04]}
set:
  dam.columns: [0.03, 5000]"
# the same mistake in every case: told for three cases, the rest not checked
expect_bad many-bad "bad.yaml: cases 3 to 99 not checked after 3 invalid ones" \
  "$base
vary:
  dam.l_hh: [0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.10]
  dam.l_v: [0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.10]"
[ "$(grep -c "is invalid" "$tmp/bad.log")" -eq 3 ] && ok || bad "many-bad: not three cases told"

echo "sweep_variants: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
