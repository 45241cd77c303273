#!/usr/bin/env bash
# Bad inputs are refused before anything is allocated, with file:line:col (or the option) and
# exit 2: placement regions, the dam's pipes, list lengths, absurd sizes, the memory and step
# estimate, sweep files, over-long files (docs/reliability.md).
set -u
bin="$1"
src_dir="$(cd "$(dirname "$0")/.." && pwd)"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
pass=0
expect() { # name, expected exit code, expected output pattern, args...
  local name="$1" code="$2" pat="$3"
  shift 3
  "$bin" "$@" >"$tmp/out" 2>"$tmp/err"
  local got=$?
  if [ "$got" -ne "$code" ] || ! grep -Eq -- "$pat" "$tmp/err" "$tmp/out"; then
    echo "FAIL $name: exit $got (want $code), output:"; cat "$tmp/err" "$tmp/out"; fail=$((fail + 1))
  else pass=$((pass + 1)); fi
}
no_memory_message() { # name: the last command did not blame the memory
  if grep -q "out of memory" "$tmp/err" "$tmp/out"; then echo "FAIL $1: reported as out of memory"; fail=$((fail + 1))
  else pass=$((pass + 1)); fi
}
y() { printf '%s\n' "$2" > "$tmp/$1.yaml"; }

# placement regions
y pile_inv 'solver: {dt: 1.0e-5, duration: 0.001}
pile: {diameters: [0.01], counts: [10], min: [0, 0, 0.5], max: [0.1, 0.1, 0.1]}
box: {on: true, min: [0, 0, 0], max: [0.1, 0.1, 0.2]}'
expect pile-inverted 2 "pile_inv.yaml:2:[0-9]+: pile.min must be below pile.max on z \(0.5 is not below 0.1\)" check "$tmp/pile_inv.yaml"
no_memory_message pile-inverted
y pile_y 'pile: {diameters: [0.01], counts: [10], min: [0, 0.1, 0], max: [0.1, 0, 0.1]}'
expect pile-inverted-y 2 "pile_y.yaml:1:[0-9]+: pile.min must be below pile.max on y" run "$tmp/pile_y.yaml" -o "$tmp/py-out"
[ ! -e "$tmp/py-out" ] && pass=$((pass + 1)) || { echo "FAIL pile-inverted-y left an output directory"; fail=$((fail + 1)); }
y pile_small 'pile: {diameters: [0.01, 0.05], counts: [10, 1], min: [0, 0, 0], max: [0.1, 0.04, 0.1]}'
expect pile-too-thin 2 "pile_small.yaml:1:[0-9]+: the pile region spans 0.04 m on y: no room for its spheres of 0.05 m" check "$tmp/pile_small.yaml"
y pack_low 'flume: {on: true, pack_height: 0.005}'
expect pack-below-roughness 2 "pack_low.yaml:1:[0-9]+: flume.pack_height: the packing box .* spans -0.007 m on z: no room for spheres of 0.02 m" check "$tmp/pack_low.yaml"
y pack_high 'flume: {on: true, wall_height: 0.3}'
expect pack-above-wall 2 "pack_high.yaml:1:[0-9]+: flume.pack_height = 0.45 m is above flume.wall_height = 0.3 m" check "$tmp/pack_high.yaml"

# the dam: inside the walls, not overlapping, below the wall top, at most 32 columns
y cols 'flume: {on: true}
dam: {columns: [0.5, 0.01]}'
expect column-outside 2 "cols.yaml:2:[0-9]+: dam.columns: 0.3 m wide flume: the column at y = 0.5 m \(diameter 0.018 m\) reaches outside the walls" check "$tmp/cols.yaml"
y cols2 'flume: {on: true}
dam: {columns: [0.1, 0.11, 0.2]}'
expect columns-overlap 2 "cols2.yaml:2:[0-9]+: dam.columns: the columns at y = 0.1 and 0.11 m overlap" check "$tmp/cols2.yaml"
y beam 'flume: {on: true, wall_height: 0.5}
dam: {top_beam: 0.49}'
expect beam-above-wall 2 "beam.yaml:2:[0-9]+: dam.top_beam: the beam with its underside at 0.49 m tops out at 0.508 m, above the 0.5 m walls" check "$tmp/beam.yaml"
y beams 'flume: {on: true}
dam: {beams: [0.04, 0.05]}'
expect beams-overlap 2 "beams.yaml:2:[0-9]+: dam.beams: the beams with undersides at 0.04 and 0.05 m overlap" check "$tmp/beams.yaml"
y wide 'flume: {on: true, width: 3, x_gate: 0.1, pack_height: 0.05}
spheres: {counts: [1, 1, 1, 1]}'
expect too-many-columns 2 "wide.yaml:1:[0-9]+: flume.width = 3 m with dam.l_h = 0.05 m needs 44 columns, more than 32" check "$tmp/wide.yaml"

# the dam's keys: one way to give the columns, the beams, the top beam (a --set overrides the
# file's); columns that fit; beams below the top beam; members inside the flume, long, apart
y ncl 'flume: {on: true}
dam: {n_columns: 5, l_h: 0.04}'
expect columns-two-keys 2 "ncl.yaml:2:[0-9]+: dam.n_columns and dam.l_h both give the columns: give one of dam.columns, dam.n_columns, dam.l_h" check "$tmp/ncl.yaml"
expect columns-set-overrides 0 "5 columns, axes at y = 44.0, 97.0, 150.0, 203.0, 256.0 mm" check "$tmp/cols.yaml" --set dam.n_columns=5
expect columns-set-two 2 "--set:2:[0-9]+: dam.columns and dam.n_columns both give the columns" check "$tmp/ncl.yaml" --set dam.n_columns=3 --set "dam.columns=[0.1]"
y bax 'flume: {on: true}
dam:
  l_v: 0.03
  beam_axes: [0.05]'
expect beams-two-keys 2 "bax.yaml:4:[0-9]+: dam.beam_axes and dam.l_v both give the beams" check "$tmp/bax.yaml"
y btop 'flume: {on: true}
dam: {beams: [0.04, 0.1], top_beam: 0.118}'
expect beams-and-top 2 "btop.yaml:2:[0-9]+: dam.beams and dam.top_beam both give the top beam: dam.beams lists every beam, the top one included" check "$tmp/btop.yaml"
y ncw 'flume: {on: true}
dam: {n_columns: 20}'
expect columns-do-not-fit 2 "ncw.yaml:2:[0-9]+: dam.n_columns: 20 columns of 0.018 m do not fit across the 0.3 m flume" check "$tmp/ncw.yaml"
y lvtop 'flume: {on: true}
dam: {l_v: 0.2}'
expect beam-above-top 2 "lvtop.yaml:2:[0-9]+: dam.l_v: the beam with its underside at 0.2 m is above the top beam \(underside 0.118 m\)" check "$tmp/lvtop.yaml"
y gaps 'flume: {on: true}
dam: {beam_gaps: [0.05, 0.06]}'
expect gaps-above-top 2 "gaps.yaml:2:[0-9]+: dam.beam_gaps: the beam with its underside at 0.128 m is above the top beam \(underside 0.118 m\): lower it, raise dam.top_beam, or remove the top beam \(dam.top_beam: false\)" check "$tmp/gaps.yaml"
expect gaps-no-top 0 "2 beams, axes at z = 59.0, 137.0 mm above the bed \(undersides 50.0, 128.0 mm; no top beam\)" check "$tmp/gaps.yaml" --set dam.top_beam=false
y axlow 'flume: {on: true}
dam: {beam_axes: [0.005]}'
expect beam-into-bed 2 "axlow.yaml:2:[0-9]+: dam.beam_axes: the beam with its axis at 0.005 m reaches into the bed" check "$tmp/axlow.yaml"
y topf 'flume: {on: true}
dam: {top_beam: ture}'
expect top-beam-word 2 "topf.yaml:2:[0-9]+: dam.top_beam: expected a number or false" check "$tmp/topf.yaml"
y none 'flume: {on: true}
dam: {n_columns: 0, l_v: 0, top_beam: false}'
expect dam-empty 2 "none.yaml:2:[0-9]+: the dam has no pipe \(no column, no beam, no member\): give it some, or dam.on: false" check "$tmp/none.yaml"
y mem 'flume: {on: true}
dam:
  members:
    - {from: [4.05, 0.15, 0.0], to: [4.2, 0.15, 0.1], diameter: 0.018}
    - {from: [4.1, 0.1, 0.1], to: [4.1, 0.1, 0.1], diameter: 0.018}'
expect member-zero-length 2 "mem.yaml:5:7: dam.members: member 1 has no length: from and to are the same point" check "$tmp/mem.yaml"
y mem2 'flume: {on: true}
dam:
  members:
    - {from: [3.9, 0.15, 0.0], to: [4.2, 0.15, 0.1], diameter: 0.018}'
expect member-upstream 2 "mem2.yaml:4:7: dam.members: member 0 \(from \[3.9, 0.15, 0\] to \[4.2, 0.15, 0.1\], diameter 0.018 m\) reaches upstream of the dam face flume.x_dam = 4 m" check "$tmp/mem2.yaml"
y mem3 'flume: {on: true}
dam:
  members:
    - {from: [4.05, 0.35, 0.0], to: [4.2, 0.15, 0.1], diameter: 0.018}'
expect member-outside 2 "mem3.yaml:4:7: dam.members: member 0 .* reaches through the wall at y = 0.3 m \(its axis to y = 0.35 m\)" check "$tmp/mem3.yaml"
y mem4 'flume: {on: true}
dam:
  members:
    - {from: [4.01, 0.05, 0.02], to: [4.01, 0.25, 0.1], diameter: 0.018}'
expect member-overlaps-column 2 "mem4.yaml:4:7: dam.members: member 0 .* overlaps the column at y = 0.048 m: their axes come 0.00223607 m apart, less than the radii.s sum 0.018 m" check "$tmp/mem4.yaml"
y mem5 'flume: {on: true}
dam:
  members:
    - {from: [4.05, 0.1, 0.0], to: [4.05, 0.1, 0.2], diameter: 0.02}
    - {from: [4.065, 0.1, 0.0], to: [4.065, 0.1, 0.2], diameter: 0.02}'
expect members-overlap 2 "mem5.yaml:5:7: dam.members: member 1 .* overlaps the member 0: their axes come 0.015 m apart, less than the radii.s sum 0.02 m" check "$tmp/mem5.yaml"
y mem6 'flume: {on: true}
dam:
  members:
    - {from: [4.05, 0.1, 0.0], to: [4.1, 0.1, 0.2], diameter: -0.02, lenght: 3}
    - {from: [4.05, 0.1], to: [4.1, 0.1, 0.2]}
    - 7'
expect member-diameter 2 "mem6.yaml:4:63: dam.members: diameter of member 0: must be > 0 and <= 1 \(m\)" check "$tmp/mem6.yaml"
expect member-unknown-key 2 "mem6.yaml:4:70: dam.members: unknown key 'lenght' in member 0 \(from, to, diameter\)" check "$tmp/mem6.yaml"
expect member-vector 2 "mem6.yaml:5:14: dam.members: from of member 1: expected \[x, y, z\]" check "$tmp/mem6.yaml"
expect member-no-diameter 2 "mem6.yaml:5:7: dam.members: member 1 has no 'diameter'" check "$tmp/mem6.yaml"
expect member-not-map 2 "mem6.yaml:6:7: dam.members: each member is a mapping" check "$tmp/mem6.yaml"
expect member-set 2 "--set:1:[0-9]+: dam.members: member 0 has no length" check "$tmp/cols.yaml" --set "dam.members=[{from: [4.1, 0.1, 0.1], to: [4.1, 0.1, 0.1], diameter: 0.01}]"

# debris as designers give it: fractions that sum to 1, one way to give the classes, drawn log
# sizes with a range (docs/scenario.md)
y grading 'flume: {on: true}
spheres:
  grading: {diameters: [0.02, 0.01], mass_fractions: [0.6, 0.5]}
  volume: 0.002'
expect grading-sum 2 "grading.yaml:3:[0-9]+: spheres.grading.mass_fractions sum to 1.1, not 1 \(within 1e-6\)" run "$tmp/grading.yaml" -o "$tmp/gr-out"
[ ! -e "$tmp/gr-out" ] && pass=$((pass + 1)) || { echo "FAIL grading-sum left an output directory"; fail=$((fail + 1)); }
y grading2 'flume: {on: true}
spheres:
  diameters: [0.02, 0.01]
  grading: {diameters: [0.02, 0.01], mass_fractions: [0.5, 0.5]}
  volume: 0.002'
expect grading-and-diameters 2 "grading2.yaml:3:[0-9]+: spheres.diameters conflicts with spheres.grading" check "$tmp/grading2.yaml"
y loglen 'flume: {on: true}
logs: {k_w: 0.1, length: {type: lognormal, mean: 0.1, sd: 0.02, min: 0.12, max: 0.2}}'
expect log-mean-outside 2 "loglen.yaml:2:[0-9]+: logs.length.mean = 0.1 m must lie in \[logs.length.min, logs.length.max\]" check "$tmp/loglen.yaml"

# list lengths: one count per diameter
y lists 'flume: {on: true}
spheres: {diameters: [0.02, 0.01, 0.005], counts: [10, 20, 30, 40]}'
expect list-lengths 2 "lists.yaml:2:[0-9]+: spheres.counts has 4 values and spheres.diameters has 3: give one count per diameter" check "$tmp/lists.yaml"
expect list-lengths-set 2 "--set:1:[0-9]+: pile.counts has 2 values and pile.diameters has 1" check "$tmp/pile_inv.yaml" --set "pile.counts=[1,2]"

# absurd sizes
y tall 'flume: {on: true, wall_height: 3e42}'
expect wall-3e42 2 "tall.yaml:1:[0-9]+: flume.wall_height: must be > 0 and <= 100 \(m\)" check "$tmp/tall.yaml"
y far 'elements:
  - {type: sphere, radius: 0.01, position: [0, 0, 1e5]}'
expect element-far 2 "far.yaml:2:1: elements: a coordinate or size of 100000 m" check "$tmp/far.yaml"
y kw 'flume: {on: true}
logs: {count: -1, k_w: 0.95, diameter: 1e-4, length: 1e-4}'
expect kw-log-count 2 "kw.yaml:2:[0-9]+: logs.k_w = 0.95 asks for .* logs, more than 1000000" check "$tmp/kw.yaml"

# the estimate: memory and steps, refused above the limits, which the user can raise
y many 'flume: {on: true, pack_height: 0.45}
spheres: {diameters: [0.02, 0.015, 0.01, 0.005], counts: [10000000, 10000000, 10000000, 10000000]}'
expect memory-estimate 2 "many.yaml: the scene needs about 76.[0-9] GiB of memory \(4.002e\+07 elements\), more than the limit of 8 GiB; .* --max-memory" check "$tmp/many.yaml"
y slow 'solver: {dt: 1.0e-12, duration: 1000, check_dt: false}
elements:
  - {type: sphere, radius: 0.01, position: [0, 0, 0]}'
expect step-estimate 2 "slow.yaml: the run takes up to 1e\+15 time steps \(solver.dt = 1e-12 s over 1000 s simulated; about 2.54 years on one core expected\); .* --max-steps" run "$tmp/slow.yaml" -o "$tmp/slow-out"
[ ! -e "$tmp/slow-out" ] && pass=$((pass + 1)) || { echo "FAIL step-estimate left an output directory"; fail=$((fail + 1)); }
expect step-estimate-raised 0 "slow.yaml: ok \(1 elements, 0 triangles; estimate: .* 1e\+15 steps" check "$tmp/slow.yaml" --max-steps 1e16
expect memory-limit-low 2 "more than the limit of 1 KiB; .* --max-memory" check "$tmp/slow.yaml" --max-memory 1K --max-steps 1e16
expect memory-limit-bad 2 "--max-memory: expected a positive size in bytes \(suffix K, M, G or T\), got '8X'" check "$tmp/slow.yaml" --max-memory 8X

# sweep files
y base 'solver: {dt: 1.0e-5, duration: 0.001}
elements:
  - {type: sphere, radius: 0.005, position: [0, 0, 0.1]}'
{
  printf 'base: base.yaml\nvary:\n'
  for k in solver.dt solver.margin solver.t_reset contact.k_n contact.k_s contact.damping contact.tan_phi contact.cohesion; do
    printf '  %s: [%s]\n' "$k" "$(seq -s, 1 32)"
  done
} > "$tmp/huge.yaml"
expect sweep-run-count 2 "huge.yaml:3:[0-9]+: vary: 1.1e\+12 runs \(cases x runs\), more than 10000" sweep "$tmp/huge.yaml" --dry-run -o "$tmp/huge-out"
{ printf 'base: base.yaml\nset:\n'; for i in $(seq 65); do printf '  k%d: 1\n' "$i"; done; } > "$tmp/sets.yaml"
expect sweep-65-sets 2 "sets.yaml:67:3: set: more than 64 keys" sweep "$tmp/sets.yaml" --dry-run -o "$tmp/sets-out"
printf 'base: base.yaml\nruns: 99999999999\n' > "$tmp/runs.yaml"
expect sweep-runs 2 "runs.yaml:2:7: runs: expected an integer from 1 to 10000" sweep "$tmp/runs.yaml" --dry-run -o "$tmp/runs-out"
printf 'base: base.yaml\nset: {solver.duration: 1.0e+6}\n' > "$tmp/long.yaml"
expect sweep-estimate 2 "long.yaml: case 0 is too large" sweep "$tmp/long.yaml" --dry-run -o "$tmp/long-out"
expect sweep-estimate-raised 0 "1 cases x 1 seeds = 1 runs" sweep "$tmp/long.yaml" --dry-run -o "$tmp/long-out" --max-steps 1e12

# materials and the springs of pairs of them (docs/scenario.md, "Materials")
y mat 'solver: {dt: 1.0e-5, duration: 0.001}
materials: [rock, wood, {name: steel}]
contact_pairs:
  - {pair: [wood, stel], tan_phi: 0.25}
  - {pair: [rock, steel], k_n: -5}
  - {pair: [rock, wood], tan_ph: 0.3}
  - {pair: [rock]}
  - {k_n: 5}
logs: {material: wod}
elements:
  - {type: sphere, radius: 0.005, position: [0, 0, 0.1], material: granite}'
expect mat-pair-unknown 2 "mat.yaml:4:19: contact_pairs.pair: unknown material 'stel' \(did you mean 'steel'\?\)" check "$tmp/mat.yaml"
expect mat-pair-negative 2 "mat.yaml:5:32: contact_pairs.k_n: must be > 0 and <= inf \(N/m\)" check "$tmp/mat.yaml"
expect mat-pair-key 2 "mat.yaml:6:26: contact_pairs: unknown key 'tan_ph' \(did you mean 'tan_phi'\?\)" check "$tmp/mat.yaml"
expect mat-pair-one 2 "mat.yaml:7:12: contact_pairs.pair: expected two material names \[a, b\]" check "$tmp/mat.yaml"
expect mat-pair-none 2 "mat.yaml:8:5: contact_pairs: each entry needs pair: \[material, material\]" check "$tmp/mat.yaml"
expect mat-key-unknown 2 "mat.yaml:9:18: logs.material: unknown material 'wod' \(did you mean 'wood'\?\)" check "$tmp/mat.yaml"
expect mat-element 2 "mat.yaml:11:68: elements.material: unknown material 'granite' \(the materials: default, rock, wood, steel; declare it under materials:\)" check "$tmp/mat.yaml"
expect mat-run 2 "mat.yaml:4:19: contact_pairs.pair: unknown material 'stel'" run "$tmp/mat.yaml" -o "$tmp/mat-out"
if [ -e "$tmp/mat-out" ]; then echo "FAIL mat-run: left $tmp/mat-out"; fail=$((fail + 1)); else pass=$((pass + 1)); fi
y matdup 'solver: {dt: 1.0e-5, duration: 0.001}
materials:
  - rock
  - default
  - rock
  - {name: wood, k_n: 3}
  - 9lives
contact_pairs:
  - {pair: [rock, wood], tan_phi: 0.3}
  - {pair: [wood, rock], k_n: 2.0e4}'
expect mat-default 2 "matdup.yaml:4:5: materials: 'default' is the material of everything given none" check "$tmp/matdup.yaml"
expect mat-twice 2 "matdup.yaml:5:5: materials: 'rock' is declared twice" check "$tmp/matdup.yaml"
expect mat-key 2 "matdup.yaml:6:18: materials: unknown key 'k_n'" check "$tmp/matdup.yaml"
expect mat-name 2 "matdup.yaml:7:5: materials: '9lives' is not a name" check "$tmp/matdup.yaml"
expect mat-pair-twice 2 "matdup.yaml:10:12: contact_pairs: the pair \[wood, rock\] is given twice \(first at line 9\)" check "$tmp/matdup.yaml"
y matdt 'solver: {duration: 0.001}
materials: [rock, steel]
contact_pairs:
  - {pair: [rock, steel], k_n: 1.0e7}
elements:
  - {type: sphere, radius: 0.005, position: [0, 0, 0.1], material: rock}
  - {type: cylinder, radius: 0.009, length: 0.1, position: [0, 0, 0], fixed: true, material: steel}'
expect mat-dt 2 "matdt.yaml:4:5: solver.dt = 1e-05 is unstable: it must be at most 2.769.*e-06 s .*k_n = 1e\+07 N/m, k_s = 4000 N/m of the pair rock-steel" check "$tmp/matdt.yaml"
expect mat-dt-ok 0 "ok \(2 elements" check "$tmp/matdt.yaml" --set solver.dt=2.5e-6
expect mat-set 2 "--set:1:15: logs.material: unknown material 'wod' \(did you mean 'wood'\?\)" check "$tmp/mat.yaml" --set logs.material=wod
expect mat-classes 2 "spheres.materials has 2 names and the spheres 4 size classes: give one material, or one per class" check "$src_dir/examples/flume_materials.yaml" --set 'spheres.materials=[rock, wood]' --set 'spheres.diameters=[0.02, 0.015, 0.01, 0.005]' --set 'spheres.counts=[1, 1, 1, 1]'

# files are read with a limit: 4 MiB, 500,000 values
python3 -c "print('#' + 'x' * (4 * 1024 * 1024))" > "$tmp/big.yaml"
expect file-too-long 2 "big.yaml: longer than 4 MiB" check "$tmp/big.yaml"
python3 -c "print('solver: [' + '0,' * 600000 + '0]')" > "$tmp/nodes.yaml"
expect too-many-values 2 "nodes.yaml:1:[0-9]+: more than 500000 values in one document" check "$tmp/nodes.yaml"

echo "inputs: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
