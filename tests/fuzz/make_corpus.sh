#!/usr/bin/env bash
# Rebuild the seed corpora of tests/fuzz/corpus/ from the examples and small valid checkpoints.
#   usage: tests/fuzz/make_corpus.sh SABODEM   (the program of a normal build)
set -euo pipefail
bin="$(realpath "$1")"
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
c="$here/corpus"
rm -rf "$c"
mkdir -p "$c/scenario" "$c/checkpoint" "$c/sweep" "$c/stl"
# scenarios: the examples that are scenarios, reduced flumes, explicit elements
for f in "$root"/examples/*.yaml; do
  grep -q '^base:' "$f" || cp "$f" "$c/scenario/$(basename "$f")"
done
cp "$here/ckpt_scenario.yaml" "$c/scenario/ckpt_scenario.yaml"
sed -e 's/counts: \[376, 891, 3010, 342\]/counts: [4, 6, 10, 3]/' -e 's/count: [0-9]*/count: 2/' \
  "$root/examples/shibuya2009.yaml" > "$c/scenario/shibuya2009_reduced.yaml"
cat > "$c/scenario/elements.yaml" <<'Y'
solver: {dt: 1.0e-5, duration: 0.001, check_dt: true}
gravity: [0, 0, -9.81]
contact: {k_n: 1.0e4, k_s: 4.0e3, damping: 0.2, tan_phi: 0.404, cohesion: 0}
box: {on: true, min: [-0.1, -0.1, 0], max: [0.1, 0.1, 0.2]}
elements:
  - {type: sphere, radius: 0.005, density: 1900, position: [0, 0, 0.1], velocity: [0.1, 0, -0.5], omega: [0, 1, 0]}
  - {type: cylinder, radius: 0.004, length: 0.05, position: [0.02, 0, 0.05], axis: [1, 1, 0], fixed: false, tag: 3}
  - {type: triangle, vertices: [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0.01]], group: 7}
output: {log_interval: 0.01, trajectory_ids: [0, 1], trajectory_interval: 1.0e-3, vtk: false, png: false}
Y
cat > "$c/scenario/pile_dam.yaml" <<'Y'
solver: {dt: 1.0e-5, duration: 0.001}
pile: {diameters: [0.01, 0.02], counts: [5, 2], density: 1900, min: [0, 0, 0.05], max: [0.1, 0.1, 0.15]}
flume: {on: true, width: 0.1, wall_height: 0.15, x_gate: 0.1, x_dam: 0.4, x_end: 0.5, roughness: false,
        pack_height: 0.1}
spheres: {diameters: [0.01], counts: [4]}
logs: {count: -1, k_w: 0.1}
dam: {on: true, pipe_diameter: 0.01, columns: [0.02, 0.05, 0.08], beams: [0.03, 0.08]}
water: {on: false}
Y
# meshes: the harness's own input read as an STL (refused: the entry's keys and the reader's
# refusal path)
printf 'solver: {dt: 1.0e-5, duration: 0.001}\nmeshes:\n  - {file: input.yaml, role: dam, scale: 0.5, translate: [0, 0, 1], rotate_deg: [0, 90, 0]}\nelements:\n  - {type: sphere, radius: 0.01, position: [0, 0, 0.1]}\n' \
  > "$c/scenario/meshes.yaml"
# checkpoints: the tiny flume's flow end (the scenario fuzz_checkpoint.c restarts against) and
# another seed's
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for seed in 2 5; do
  "$bin" run "$here/ckpt_scenario.yaml" --seed $seed --checkpoint-at flow_end -o "$tmp/s$seed" >/dev/null 2>&1
  cp "$tmp/s$seed/flow_end.ckpt" "$c/checkpoint/tiny_flume_seed$seed.ckpt"
done
# and one with materials (a MATL section, material ids on the bodies and triangles)
{ sed -e 's/^spheres: {/spheres: {materials: [rock], /' -e 's/^logs: {/logs: {material: wood, /' \
      -e 's/^dam: {/dam: {material: steel, /' -e 's/^flume: {on: true,/flume: {on: true, gate_material: steel,/' \
      "$here/ckpt_scenario.yaml"
  printf 'materials: [rock, wood, steel]\ncontact_pairs:\n  - {pair: [rock, steel], tan_phi: 0.3, k_n: 2.0e4}\n'
  printf '  - {pair: [wood, default], damping: 0.3}\n'; } > "$tmp/materials.yaml"
"$bin" run "$tmp/materials.yaml" --checkpoint-at flow_end -o "$tmp/mat" >/dev/null 2>&1
cp "$tmp/mat/flow_end.ckpt" "$c/checkpoint/tiny_flume_materials.ckpt"
# sweeps: the examples' matrices on the harness's base.yaml, and a few shapes
for f in "$root"/examples/*.yaml; do
  grep -q '^base:' "$f" && sed 's/^base: .*/base: base.yaml/' "$f" > "$c/sweep/$(basename "$f")"
done
printf 'base: base.yaml\nruns: 2\nseed_base: 7\nparallel: 1\nvary:\n  dam.l_h: [0.03, 0.05]\n  solver.dt: [1.0e-5, 2.0e-5]\nset:\n  solver.duration: 0.002\n' \
  > "$c/sweep/branch.yaml"
printf 'base: base.yaml\n' > "$c/sweep/minimal.yaml"
# named variants (several keys each, one of none) and list values (a list of lists, vectors)
cat > "$c/sweep/variants.yaml" <<'Y'
base: base.yaml
runs: 2
vary:
  layout:
    narrow: {dam.l_h: 0.04, dam.l_v: 0.03}
    wide: {dam.l_h: 0.06, dam.l_v: 0, solver.dt: 2.0e-5}
    plain: {}
  dam.columns: [[0.05, 0.1, 0.15], [0.07, 0.14]]
  gravity: [[0, 0, -9.81], [0, 0, -1.62]]
set:
  solver.duration: 0.002
  dam.beams: [0.03, 0.08]
  output.trajectory_ids: [0]
Y

# STL meshes: the test fixtures, and a cube in each format and in the ASCII grammar's variants
cp "$root/tests/data/plane.stl" "$root/tests/data/plane_bin.stl" "$c/stl/"
python3 - "$c/stl" <<'PY'
import struct, sys
d = sys.argv[1]
q = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
faces = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4), (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6),
         (3, 0, 4), (3, 4, 7)]
tris = [tuple(q[i] for i in f) for f in faces]
def ascii(tris, kw=lambda s: s, nl="\n", name="cube"):
    s = kw("solid") + " " + name + nl
    for t in tris:
        s += "  " + kw("facet normal") + " 0 0 0" + nl + "    " + kw("outer loop") + nl
        for v in t:
            s += "      " + kw("vertex") + " %g %g %g" % v + nl
        s += "    " + kw("endloop") + nl + "  " + kw("endfacet") + nl
    return s + kw("endsolid") + " " + name + nl
def binary(tris, header=b"cube"):
    b = header.ljust(80, b" ") + struct.pack("<I", len(tris))
    for t in tris:
        b += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *v) for v in t) + b"\0\0"
    return b
open(d + "/cube.stl", "w").write(ascii(tris))
open(d + "/cube_upper_crlf.stl", "w", newline="").write(ascii(tris, str.upper, "\r\n"))
open(d + "/cube_one_line.stl", "w").write(ascii(tris[:4], nl=" "))
open(d + "/two_solids.stl", "w").write(ascii(tris[:6], name="a") + ascii(tris[6:], name="b"))
open(d + "/degenerate.stl", "w").write(ascii(tris[:2] + [((0, 0, 0), (1, 1, 1), (2, 2, 2))]))
open(d + "/cube_bin.stl", "wb").write(binary(tris))
open(d + "/cube_bin_solid_header.stl", "wb").write(binary(tris, b"solid cube"))
PY
du -sh "$c"
