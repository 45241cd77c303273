#!/usr/bin/env bash
# Every example scenario stays valid and runs: `sabodem check` builds it, and a run of a few
# time steps (every phase cut to 2 ms) ends with its summary. The field example also scales
# by its one key, flume.volume_factor (docs/field.md).
set -u
bin="$1"
src_dir="$(cd "$(dirname "$0")/.." && pwd)"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
pass=0
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL $1"; fail=$((fail + 1)); }
short=(--set solver.duration=0.002 --set phases.packing_time=0.002 --set phases.flow_limit=0.002
       --set phases.capture_limit=0.002 --set output.png=false --set output.vtk=false)
for f in "$src_dir"/examples/*.yaml; do
  grep -q '^base:' "$f" && continue # a sweep (tests/sweep_test.sh)
  name=$(basename "$f" .yaml)
  if "$bin" check "$f" >"$tmp/$name.check" 2>&1; then ok; else bad "check $name:"; cat "$tmp/$name.check"; fi
  if "$bin" run "$f" -o "$tmp/$name" --threads 1 --progress 0 "${short[@]}" >"$tmp/$name.run" 2>&1 &&
     grep -Eq '"status":[[:space:]]*"finished"' "$tmp/$name/summary.json"; then ok
  else bad "run $name:"; cat "$tmp/$name.run"; fi
done
# the field example: 887 boulders and 21 logs as given; the full front at volume_factor 1
f="$src_dir/examples/field_torrent.yaml"
grep -q "spheres class 3: d = 400.0 mm, 597," "$tmp/field_torrent.check" && grep -q "logs: 21," "$tmp/field_torrent.check" \
  && ok || bad "field_torrent: not 597 boulders of 0.4 m and 21 logs at volume_factor 0.2"
if "$bin" check "$f" --set flume.volume_factor=1 >"$tmp/full.check" 2>&1 && grep -q "spheres class 3: d = 400.0 mm, 2984," "$tmp/full.check" \
   && grep -q "logs: 105," "$tmp/full.check"; then ok; else bad "field_torrent at volume_factor 1:"; cat "$tmp/full.check"; fi
echo "examples: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
