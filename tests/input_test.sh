#!/usr/bin/env bash
# Bad inputs are refused before anything is allocated, with file:line:col (or the option) and
# exit 2: placement regions, the dam's pipes, list lengths, absurd sizes, the memory and step
# estimate, sweep files, over-long files (docs/reliability.md).
set -u
bin="$1"
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
expect step-estimate 2 "slow.yaml: the run takes 1e\+15 time steps \(solver.dt = 1e-12 s over 1000 s simulated\), about 579 days on one core; .* --max-steps" run "$tmp/slow.yaml" -o "$tmp/slow-out"
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

# files are read with a limit: 4 MiB, 500,000 values
python3 -c "print('#' + 'x' * (4 * 1024 * 1024))" > "$tmp/big.yaml"
expect file-too-long 2 "big.yaml: longer than 4 MiB" check "$tmp/big.yaml"
python3 -c "print('solver: [' + '0,' * 600000 + '0]')" > "$tmp/nodes.yaml"
expect too-many-values 2 "nodes.yaml:1:[0-9]+: more than 500000 values in one document" check "$tmp/nodes.yaml"

echo "inputs: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
