#!/usr/bin/env bash
# Command-line behaviour: bad scenarios are refused with file:line:col, exit 2 and no output
# directory; check validates; --set overrides; unknown options fail.
set -u
bin="$1"
src_dir="$(cd "$(dirname "$0")/.." && pwd)"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
pass=0
expect() { # name, expected exit code, expected stderr pattern, args...
  local name="$1" code="$2" pat="$3"
  shift 3
  "$bin" "$@" >"$tmp/out" 2>"$tmp/err"
  local got=$?
  if [ "$got" -ne "$code" ] || ! grep -Eq -- "$pat" "$tmp/err" "$tmp/out"; then
    echo "FAIL $name: exit $got (want $code), output:"; cat "$tmp/err" "$tmp/out"; fail=$((fail + 1))
  else pass=$((pass + 1)); fi
}
base='solver: {dt: 1.0e-5, duration: 0.001}
gravity: [0, 0, -9.81]
elements:
  - {type: sphere, radius: 0.005, density: 1900, position: [0, 0, 0.1]}
'
printf '%s' "$base" > "$tmp/good.yaml"
expect good-check 0 "ok \(1 elements" check "$tmp/good.yaml"
expect good-run 0 "done" run "$tmp/good.yaml" -o "$tmp/good-out"
[ -f "$tmp/good-out/summary.json" ] && pass=$((pass + 1)) || { echo "FAIL good-run: no summary.json"; fail=$((fail + 1)); }

# summary.json is JSON whatever the scenario's file name holds (a quote, a backslash, a
# newline): read back, it gives the name, the steps and a parameter exactly
odd="$tmp/we\"ird\\na
me.yaml"
printf '%s' "$base" > "$odd"
expect odd-name 0 "done" run "$odd" -o "$tmp/odd-out"
SD_ODD="$odd" /usr/bin/python3 -c "
import json, os, sys
d = json.load(open('$tmp/odd-out/summary.json'))
sys.exit(not (d['scenario'] == os.environ['SD_ODD'] and d['steps'] == 100 and d['parameters']['solver.dt'] == 1e-5
              and d['parameters']['gravity'] == [0, 0, -9.81] and d['status'] == 'finished'))" \
  && pass=$((pass + 1)) || { echo "FAIL odd-name: summary.json not valid or not exact"; cat "$tmp/odd-out/summary.json"; fail=$((fail + 1)); }

printf '%s  - {type: sphere, radius: -0.01, position: [0, 0, 0]}\n' "$base" > "$tmp/neg.yaml"
expect negative-radius 2 "neg.yaml:5:[0-9]+: elements.radius: expected a positive number" run "$tmp/neg.yaml" -o "$tmp/neg-out"
[ ! -e "$tmp/neg-out" ] && pass=$((pass + 1)) || { echo "FAIL negative-radius left an output directory"; fail=$((fail + 1)); }

printf 'solver: {dt: 1.0e-5, durration: 1}\n' > "$tmp/key.yaml"

# "did you mean": the nearest key, section, element key or type, command, option
printf 'solvr: {dt: 1.0e-5}\nelements:\n  - {type: sphre, radius: 0.01}\n  - {type: sphere, radus: 0.01}\n' > "$tmp/near.yaml"
expect near-key 2 "key.yaml:1:22: unknown key 'solver.durration' \(did you mean 'solver.duration'\?\)" check "$tmp/key.yaml"
expect near-section 2 "near.yaml:1:1: unknown key 'solvr' \(did you mean 'solver'\?\)" check "$tmp/near.yaml"
expect near-type 2 "near.yaml:3:12: elements.type: unknown element type 'sphre' \(did you mean 'sphere'\?\)" check "$tmp/near.yaml"
expect near-elem-key 2 "near.yaml:4:20: elements: unknown key 'radus' \(did you mean 'radius'\?\)" check "$tmp/near.yaml"
expect near-set 2 "--set:1:1: unknown key 'contact.kn' \(did you mean 'contact.k_n'\?\)" check "$tmp/good.yaml" --set contact.kn=5
expect near-none 2 "unknown key 'zzz'$" check "$tmp/good.yaml" --set zzz=5
expect near-command 2 "unknown command 'chek' \(did you mean 'check'\?\)" chek "$tmp/good.yaml"
expect near-option 2 "sabodem run: unknown or incomplete option '--thread' \(did you mean '--threads'\?\)" run "$tmp/good.yaml" --thread 2
expect near-sweep-option 2 "unknown or incomplete option '--dryrun' \(did you mean '--dry-run'\?\)" sweep x.yaml --dryrun
expect near-abbrev 2 "unknown or incomplete option '--mark' \(did you mean '--markdown'\?\)" params --mark

printf 'solver: {dt: fast}\n' > "$tmp/type.yaml"
expect wrong-type 2 "type.yaml:1:[0-9]+: solver.dt: expected a number" check "$tmp/type.yaml"

printf 'solver:\n  dt: 1.0e-3\nelements:\n  - {type: sphere, radius: 0.0025, position: [0, 0, 0]}\n' > "$tmp/dt.yaml"
expect unstable-dt 2 "dt.yaml:2:[0-9]+: solver.dt = 0.001 is unstable" run "$tmp/dt.yaml" -o "$tmp/dt-out"
[ ! -e "$tmp/dt-out" ] && pass=$((pass + 1)) || { echo "FAIL unstable-dt left an output directory"; fail=$((fail + 1)); }

printf 'flume: {on: true, x_gate: 4.2, x_dam: 4.0}\n' > "$tmp/gate.yaml"
expect gate-beyond-dam 2 "gate.yaml:1:[0-9]+: flume.x_gate must be upstream of flume.x_dam" check "$tmp/gate.yaml"

expect unreadable 2 "nonexistent.yaml: cannot open" check "$tmp/nonexistent.yaml"
printf 'solver: {dt: [1, 2\n' > "$tmp/syntax.yaml"
expect yaml-syntax 2 "syntax.yaml:[0-9]+:[0-9]+:" check "$tmp/syntax.yaml"
expect set-override 2 "--set:1:[0-9]+: contact.k_n: must be > 0" check "$tmp/good.yaml" --set contact.k_n=-5
expect set-unknown 2 "--set:1:1: unknown key 'contact.kn'" check "$tmp/good.yaml" --set contact.kn=5
expect bad-option 2 "unknown or incomplete option" run "$tmp/good.yaml" --frobnicate
expect params 0 "solver.dt" params
expect version 0 "^sabodem [0-9]+\.[0-9]+\.[0-9]+$" --version
expect run-help 0 "--restart CHECKPOINT      continue from such a checkpoint" run --help
expect sweep-help 0 "--no-branch   every run packs and flows on its own" sweep --help
expect threads-bad 2 "--threads: expected an integer from 0 to 1024, got 'x'" run "$tmp/good.yaml" --threads x
expect seed-bad 2 "--seed: expected an integer from 0 to 2147483647, got '1.5'" run "$tmp/good.yaml" --seed 1.5

# branching flags: bad values and files are refused, naming them
expect checkpoint-at-bad 2 "--checkpoint-at: unknown point 'capture'" run "$src_dir/examples/flume_small.yaml" --checkpoint-at capture
expect checkpoint-at-noflume 2 "good.yaml: --checkpoint-at needs a flume scenario" run "$tmp/good.yaml" --checkpoint-at flow_end -o "$tmp/ck-out"
expect restart-missing 2 "nothere.ckpt: cannot open" run "$src_dir/examples/flume_small.yaml" --restart "$tmp/nothere.ckpt" -o "$tmp/rs-out"
printf 'not a checkpoint' > "$tmp/junk.ckpt"
expect restart-junk 2 "junk.ckpt: not a sabodem checkpoint" run "$src_dir/examples/flume_small.yaml" --restart "$tmp/junk.ckpt" -o "$tmp/rs-out"
[ ! -e "$tmp/rs-out" ] && pass=$((pass + 1)) || { echo "FAIL bad restart left an output directory"; fail=$((fail + 1)); }
expect restart-check 2 "unknown or incomplete option '--restart'" check "$src_dir/examples/flume_small.yaml" --restart "$tmp/junk.ckpt"
# the paper's Table 2 matrix: 60 runs from 15 shared flows, listed without running
expect designer-debris 0 "logs: [0-9]+, solid volume .* sizes drawn per log" check "$src_dir/examples/debris_designer.yaml"
expect table2-dry-run 0 "branching on dam.l_v: 15 shared flows" sweep "$src_dir/examples/shibuya2009-table2.yaml" --dry-run -o "$tmp/t2"
[ "$(grep -c '^run case' "$tmp/out")" -eq 60 ] && [ ! -e "$tmp/t2" ] && pass=$((pass + 1)) || { echo "FAIL table2 dry run"; fail=$((fail + 1)); }
expect sweep-parallel-bad 2 "--parallel: expected a positive integer" sweep "$src_dir/examples/shibuya2009-table2.yaml" --parallel 0

# Ctrl-C: exit 130, summary and VTK series closed and valid. The interrupt comes once the
# flow phase has started (not after a fixed time: a faster engine would finish first), and a
# long capture limit keeps the run from ending on its own. A closed terminal (SIGHUP) the same.
interrupted() { # name, signal
  "$bin" run "$src_dir/examples/flume_small.yaml" -o "$tmp/$1" --progress 0 --set output.png=false --set phases.capture_limit=60 \
    >"$tmp/$1.log" 2>&1 &
  local pid=$! code
  for _ in $(seq 600); do grep -q '^phase=flow' "$tmp/$1.log" 2>/dev/null && break; sleep 0.1; done
  kill "-$2" $pid
  wait $pid
  code=$?
  if [ "$code" -eq 130 ] && /usr/bin/python3 -c "import json,sys; d=json.load(open('$tmp/$1/summary.json')); sys.exit(d['status']!='interrupted')" \
     && /usr/bin/python3 "$src_dir/scripts/check_vtk.py" "$tmp/$1/series.pvd" >/dev/null && [ -z "$(ls "$tmp/$1" | grep -E '\.tmp|XXXX')" ]; then
    pass=$((pass + 1)); else echo "FAIL $1 (SIG$2): exit $code"; cat "$tmp/$1.log"; ls "$tmp/$1"; fail=$((fail + 1)); fi
}
interrupted int INT
interrupted hup HUP

# a closed pipe downstream (SIGPIPE) stops a run as Ctrl-C does: a summary that says so, not a
# run killed without one
"$bin" run "$src_dir/examples/flume_small.yaml" -o "$tmp/pipe" --set output.png=false --set output.log_interval=0.001 \
  --set phases.capture_limit=60 2>&1 | head -n 3 >/dev/null
if /usr/bin/python3 -c "import json,sys; d=json.load(open('$tmp/pipe/summary.json')); sys.exit(d['status']!='interrupted')"; then
  pass=$((pass + 1)); else echo "FAIL sigpipe: no interrupted summary"; ls "$tmp/pipe"; fail=$((fail + 1)); fi

# a full disk, as any user can make one: files may not grow past 8 KiB (ulimit -f; SIGXFSZ
# ignored, so a write past it fails with EFBIG). series.csv, a row a millisecond, fills it first:
# the run stops with an error naming the file and exit 1, and its summary says so; not a run
# that says done (tests/restart_test.sh fills a real file system, as root)
(ulimit -f 8 && trap '' XFSZ && exec "$bin" run "$src_dir/examples/flume_small.yaml" -o "$tmp/full" --set output.png=false \
  --set output.vtk=false --set output.log_interval=0.001) >"$tmp/out" 2>"$tmp/err"
code=$?
if [ "$code" -eq 1 ] && grep -q "full/series.csv: cannot write: File too large" "$tmp/err"; then pass=$((pass + 1))
else echo "FAIL disk-full: exit $code (want 1), output:"; cat "$tmp/err" "$tmp/out"; fail=$((fail + 1)); fi
/usr/bin/python3 -c "import json,sys; sys.exit(json.load(open('$tmp/full/summary.json'))['status'] != 'output failed')" \
  && pass=$((pass + 1)) || { echo "FAIL disk-full: summary"; fail=$((fail + 1)); }

# inputs that once crashed or hung the readers: refused with a clear message
python3 -c "print('solver: ' + '[' * 60000 + ']' * 60000)" > "$tmp/deep.yaml"
expect yaml-too-deep 2 "deep.yaml:1:[0-9]+: nested deeper than 64 levels" check "$tmp/deep.yaml"
printf 'solver:\n  dt: 1.0e-5\n  margin: 5.0e-3\n  dt: 2.0e-5\n' > "$tmp/dup.yaml"
expect yaml-duplicate 2 "dup.yaml:4:3: duplicate key 'dt'" check "$tmp/dup.yaml"
expect restart-device 2 "/dev/zero: not a regular file" run "$src_dir/examples/flume_small.yaml" --restart /dev/zero -o "$tmp/rz-out"

# the side views of the arrival and the end, drawn together when the run ends: both PNGs there
# (with Debian's python3-matplotlib, which scripts/setup.sh installs), or the note for each.
# The dam has a member too (a strut behind it, 56 deg up, 72.1 mm long: its loads below)
"$bin" run "$src_dir/examples/flume_small.yaml" -o "$tmp/png" --set output.png=true --set phases.capture_limit=0.05 \
  --set 'dam.members=[{from: [0.84, 0.06, 0.0], to: [0.88, 0.06, 0.06], diameter: 0.012}]' >"$tmp/png.log" 2>&1
code=$?
if /usr/bin/python3 -c "import matplotlib" 2>/dev/null; then
  png_ok=1
  for f in side_arrival.png side_final.png; do
    [ "$(head -c 8 "$tmp/png/$f" 2>/dev/null | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ] || png_ok=0
  done
else
  png_ok=$([ "$(grep -c 'not drawn' "$tmp/png.log")" -eq 2 ] && echo 1 || echo 0)
fi
if [ "$code" -eq 0 ] && [ "$png_ok" -eq 1 ]; then pass=$((pass + 1)); else
  echo "FAIL side views: exit $code"; cat "$tmp/png.log"; ls "$tmp/png"; fail=$((fail + 1)); fi
# in a log, a progress line at most every 5 s of wall time (--progress's default): no more
# lines than 2 + wall / 5 (the first line comes at once)
lines=$(grep -c '^phase=' "$tmp/png.log")
most=$(/usr/bin/python3 -c "import json; print(2 + int(json.load(open('$tmp/png/summary.json'))['wall_time_s'] / 5))")
if [ "$lines" -ge 1 ] && [ "$lines" -le "$most" ]; then pass=$((pass + 1)); else
  echo "FAIL progress lines in a log: $lines (at most $most)"; fail=$((fail + 1)); fi
expect progress-bad 2 "--progress: expected seconds from 0 to 86400, got '-1'" run "$tmp/good.yaml" --progress -1 -o "$tmp/pb"

# check describes the paper's flume in design terms; the numbers by hand (SPEC §8): 4 columns
# of pitch 50 + 18 mm centred across 300 mm (axes 150 -/+ 34, 102); wall gaps 48 - 9 = 39 mm;
# beam axes at 40 + 9 and 118 + 9 mm; 150 logs of 10 x 100 mm = 1.178 L against the spheres'
# 4.748 L: K_w = 19.88 %
expect check-dam-columns 0 "4 columns, axes at y = 48.0, 116.0, 184.0, 252.0 mm" check "$src_dir/examples/shibuya2009.yaml"
for pat in "clear gaps across \(wall, between columns, wall\): 39.0, 50.0, 50.0, 50.0, 39.0 mm" \
           "2 beams, axes at z = 49.0, 127.0 mm" "l_H/d_max = 2.50, l_H/L_log = 0.50" "l_V/d_max = 2.00" \
           "logs: 150, d = 10.0 mm, L = 100.0 mm, solid volume 1.178 L" "K_w = .* = 19.88 %" \
           "spheres class 2: d = 10.0 mm, 3010, solid volume 1.576 L"; do
  if grep -Eq -- "$pat" "$tmp/out"; then pass=$((pass + 1)); else echo "FAIL check report: no '$pat'"; cat "$tmp/out"; fail=$((fail + 1)); fi
done
expect check-one-material 0 "materials: one: every contact K_n = 10000 N/m, K_s = 4000 N/m, h = 0.2, tan phi = 0.404, c = 0 N" check "$src_dir/examples/shibuya2009.yaml"
expect check-no-beam 0 "no intermediate beam: bed to the top beam 118.0 mm = 5.90 d_max" check "$src_dir/examples/shibuya2009.yaml" --set dam.l_v=0
# materials: what uses each, and each pair's springs (* given in contact_pairs, the rest contact.*'s)
expect check-materials 0 "materials: default \(unused\), rock \(spheres, roughness\), wood \(logs\), steel \(dam, gate\), concrete \(bed, walls\)" check "$src_dir/examples/flume_materials.yaml"
for pat in " rock-rock +10000 +4000 +0.2 +0.404 +0$" "\*rock-steel +20000 +8000 +0.2 +0.3 +0$" "\*wood-steel +10000 +4000 +0.3 +0.25 +0$"; do
  if grep -Eq -- "$pat" "$tmp/out"; then pass=$((pass + 1)); else echo "FAIL check materials: no '$pat'"; cat "$tmp/out"; fail=$((fail + 1)); fi
done
# the dam of examples/shibuya2009-members.yaml: 5 columns at 44 + 53 k mm (clear gaps (300 -
# 5 x 18)/6 = 35 mm), beams by their gaps 30 and 40 mm (axes 30 + 9 = 39, 30 + 18 + 40 + 9 = 97
# mm) under the top beam (127 mm), a strut of sqrt(160^2 + 110^2) = 194.2 mm at atan(110/160) =
# 34.5 deg
expect check-members 0 "5 columns, axes at y = 44.0, 97.0, 150.0, 203.0, 256.0 mm, from the bed to 136.0 mm" check "$src_dir/examples/shibuya2009-members.yaml"
for pat in "clear gaps across \(wall, between columns, wall\): 35.0, 35.0, 35.0, 35.0, 35.0, 35.0 mm" \
           "3 beams, axes at z = 39.0, 97.0, 127.0 mm above the bed \(undersides 30.0, 88.0, 118.0 mm; the top beam at dam.top_beam\)" \
           "clear gaps up \(bed, between beams, above the top beam to the wall top\): 30.0, 40.0, 12.0, 364.0 mm" \
           "0: from \[4.2000, 0.1500, 0.0000\] to \[4.0400, 0.1500, 0.1100\] m, d = 18.0 mm, length 194.2 mm, 34.5 deg from the bed plane"; do
  if grep -Eq -- "$pat" "$tmp/out"; then pass=$((pass + 1)); else echo "FAIL check report: no '$pat'"; cat "$tmp/out"; fail=$((fail + 1)); fi
done
expect check-png-noflume 2 "has no flume" check "$tmp/good.yaml" --png "$tmp/x.png"
# check --png: the design drawn (a PNG), or, without matplotlib, exit 1 saying so; its
# temporary data removed either way
"$bin" check "$src_dir/examples/flume_small.yaml" --png "$tmp/design.png" >"$tmp/design.log" 2>&1
code=$?
if /usr/bin/python3 -c "import matplotlib" 2>/dev/null; then
  [ "$code" -eq 0 ] && [ "$(head -c 8 "$tmp/design.png" 2>/dev/null | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ]
else
  [ "$code" -eq 1 ] && grep -q "not drawn" "$tmp/design.log"
fi
png_ok=$?
left=$(ls "${TMPDIR:-/tmp}" | grep -c "^sabodem-design-")
if [ "$png_ok" -eq 0 ] && [ "$left" -eq 0 ]; then pass=$((pass + 1)); else
  echo "FAIL check --png: exit $code, $left temporary directories left"; cat "$tmp/design.log"; fail=$((fail + 1)); fi

# a flume run's summary: valid JSON with the trap ratio, its classes, the pipes and the parameters
/usr/bin/python3 -c "
import json, sys
d = json.load(open('$tmp/png/summary.json'))
ok = 0 <= d['trap_ratio'] <= 1 and len(d['trap_ratio_class']) == len(d['parameters']['spheres.diameters'])
ok = ok and len(d['pipes']) == d['elements']['pipes'] > 0 and all(p['peak_force_N'] >= 0 for p in d['pipes'])
ok = ok and d['parameters']['flume.x_dam'] == 0.8 and d['capture_limit_s'] == 0.05 and len(d['state_hash']) == 16
sys.exit(not ok)" && pass=$((pass + 1)) || { echo "FAIL flume summary.json"; cat "$tmp/png/summary.json"; fail=$((fail + 1)); }

# the man page and the bash completion come from the same tables as params and --help: every
# key and every option of every command is in the man page (roff-escaped); the completion
# offers every key after --set, a command's options after '-', the commands first
"$bin" params | awk '{print $1}' > "$tmp/keys"
[ "$(wc -l < "$tmp/keys")" -gt 50 ] || { echo "FAIL params lists too few keys"; fail=$((fail + 1)); }
"$bin" man > "$tmp/sabodem.1"
man_ok=1
while read -r k; do grep -qxF ".B $(printf '%s' "$k" | sed 's/-/\\-/g')" "$tmp/sabodem.1" || { echo "man: no $k"; man_ok=0; }; done < "$tmp/keys"
for c in run check sweep params man completion; do
  "$bin" $c --help | head -1 | grep -q "usage: sabodem $c" || { echo "no help for $c"; man_ok=0; }
  grep -qxF ".B $c" "$tmp/sabodem.1" || { echo "man: no command $c"; man_ok=0; }
done
for o in --output --set --threads --seed --checkpoint-at --restart --parallel --dry-run --no-branch --markdown; do
  grep -qF -- "$(printf '%s' "$o" | sed 's/-/\\-/g')" "$tmp/sabodem.1" || { echo "man: no $o"; man_ok=0; }
done
if command -v groff >/dev/null; then groff -k -man -Tutf8 -ww -z "$tmp/sabodem.1" 2>"$tmp/groff.err"; [ -s "$tmp/groff.err" ] && { cat "$tmp/groff.err"; man_ok=0; }; fi
[ "$man_ok" -eq 1 ] && pass=$((pass + 1)) || { echo "FAIL man page out of step with the tables"; fail=$((fail + 1)); }
"$bin" completion bash > "$tmp/sabodem.bash"
complete_words() { # words of the command line being completed (the last one is the word under the cursor)
  bash -c 'compopt() { :; }; source "$1"; shift; COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1)); _sabodem; printf "%s\n" "${COMPREPLY[@]}"' \
    _ "$tmp/sabodem.bash" "$@" | sort
}
comp_ok=1
[ "$(complete_words sabodem run x.yaml --set '' | sed 's/=$//' | sort)" = "$(sort "$tmp/keys")" ] || { echo "completion: --set keys"; comp_ok=0; }
[ "$(complete_words sabodem run x.yaml --set solver.d | tr '\n' ' ')" = "solver.dt= solver.duration= " ] || { echo "completion: solver.d"; comp_ok=0; }
[ "$(complete_words sabodem sweep x.yaml --d)" = "--dry-run" ] || { echo "completion: sweep --d"; comp_ok=0; }
[ "$(complete_words sabodem ch)" = "check" ] || { echo "completion: ch"; comp_ok=0; }
[ "$(complete_words sabodem run x.yaml --checkpoint-at '')" = "flow_end" ] || { echo "completion: flow_end"; comp_ok=0; }
[ "$comp_ok" -eq 1 ] && pass=$((pass + 1)) || { echo "FAIL bash completion"; fail=$((fail + 1)); }

# the run's debris account and pipe loads (docs/loads.md): held + in the channel + passed is all
# the debris released, P_V is (held + channel) / all, the capture's end is named, pipes.csv has a
# row per pipe per sample with the moment of its columns' resultant inside each span
if /usr/bin/python3 - "$tmp/png" <<'PY'
import csv, json, sys
d = sys.argv[1]
s = json.load(open(d + "/summary.json"))
v = s["debris_m3"]
total = s["solid_volume_m3"]["spheres"] + s["solid_volume_m3"]["logs"]
assert abs(v["held_at_dam"] + v["in_channel"] + v["passed"] - total) <= 1e-6 * total, (v, total)
assert abs((v["held_at_dam"] + v["in_channel"]) / total - s["trap_ratio"]) <= 2e-6, (v, s["trap_ratio"])
assert s["capture"] == "cut by its time limit", s["capture"]
rows = list(csv.DictReader(open(d + "/pipes.csv")))
n = len(s["pipes"])
assert n == 5 and len(rows) % n == 0 and len(rows) >= 2 * n, (n, len(rows))
# the member: last, its ends and span (its length), no axis coordinate in pipes.csv
m = s["pipes"][4]
assert m["kind"] == "member" and m["member"] == 0 and m["from_m"] == [0.84, 0.06, 0.0] and m["to_m"] == [0.88, 0.06, 0.06], m
assert abs(m["span_m"] - (0.04 ** 2 + 0.06 ** 2) ** 0.5) < 1e-15 and m["diameter_m"] == 0.012, m
assert all(r["kind"] == "member" and r["axis_m"] == "" for r in rows if r["pipe"] == "4"), rows[4]
assert [p["kind"] for p in s["pipes"][:4]] == ["column", "column", "beam", "beam"], s["pipes"]
for r in rows:
    span = s["pipes"][int(r["pipe"])]["span_m"]
    assert 0.0 <= float(r["s_m"]) <= span and float(r["m_bend_Nm"]) >= 0.0, r
    f = (float(r["fx_N"]) ** 2 + float(r["fy_N"]) ** 2 + float(r["fz_N"]) ** 2) ** 0.5
    assert abs(f - float(r["f_N"])) <= 1e-5 * max(f, 1e-9), r
# every step's force goes into some sample's interval peak: the largest is the run's peak
pk, ipk = max(p["peak_force_N"] for p in s["pipes"]), max(float(r["f_peak_interval_N"]) for r in rows)
assert pk > 0 and abs(pk - ipk) <= 1e-6 * pk, (pk, ipk)
# impact events: events.csv has a row per event of summary.json's counts, their largest peaks,
# impulses and energies, each peak at least the threshold and at most the pipe's peak
ev = list(csv.DictReader(open(d + "/events.csv")))
T = s["event_threshold_N"]
assert T > 0 and sum(p["events"]["count"] for p in s["pipes"]) == len(ev) > 0, (T, len(ev))
for k, p in enumerate(s["pipes"]):
    mine = [r for r in ev if int(r["pipe"]) == k]
    assert len(mine) == p["events"]["count"], (k, len(mine))
    for key, col in (("largest_peak_N", "peak_N"), ("largest_impulse_Ns", "impulse_Ns"), ("largest_energy_J", "energy_J")):
        got = max((float(r[col]) for r in mine), default=0.0)
        assert abs(got - p["events"][key]) <= 1e-6 * max(got, 1e-12), (k, key, got, p["events"][key])
    for r in mine:
        assert T < float(r["peak_N"]) <= p["peak_force_N"] * (1 + 1e-6) and float(r["duration_s"]) > 0, r
        assert r["end"] in ("fell", "sustained", "run_end") and float(r["energy_J"]) >= 0, r
# the debris released: the classes' counts as spheres.counts, the logs' count as the run's
rel = s["debris_released"]
assert [c["count"] for c in rel["spheres"]] == s["parameters"]["spheres.counts"], rel
assert rel["classes_from"] == "spheres.counts" and rel["logs"]["count"] == s["elements"]["logs"], rel
PY
then pass=$((pass + 1)); else echo "FAIL debris account / pipe loads / events in summary.json, pipes.csv, events.csv"; fail=$((fail + 1)); fi

# docs/scenario.md carries the same table the loader checks
"$bin" params --markdown > "$tmp/params.md"
if awk '/^## Keys/{f=1;next} f && NF' "$src_dir/docs/scenario.md" | diff -q - "$tmp/params.md" >/dev/null; then
  pass=$((pass + 1)); else echo "FAIL docs/scenario.md is out of date: regenerate from 'sabodem params --markdown'"; fail=$((fail + 1)); fi

echo "cli: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
