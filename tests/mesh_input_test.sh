#!/usr/bin/env bash
# Bad STL meshes (docs/meshes.md) are refused by `sabodem check` and `run` with the scenario's
# file:line:col, the STL file and the line (ASCII) or triangle index and byte offset (binary),
# exit 2 and no output directory; zero-area triangles are dropped with a warning; a flume without
# its flat bed needs a bed mesh and no roughness.
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
# a scenario that loads one mesh (the file name relative to the scenario's directory)
scen() { # name, mesh file, [extra YAML]
  printf 'solver: {dt: 1.0e-5, duration: 0.001}\nmeshes:\n  - {file: %s, role: bed}\n%s\n' "$2" "${3:-}" > "$tmp/$1.yaml"
}
# STL files: a good two-triangle plane in ASCII and binary, and broken variants of each
python3 - "$tmp" <<'PY'
import struct, sys
d = sys.argv[1]
tris = [((0, 0, 0), (1, 0, 0), (1, 1, 0)), ((0, 0, 0), (1, 1, 0), (0, 1, 0))]
def ascii(tris, name="plane"):
    s = "solid %s\n" % name
    for t in tris:
        s += "  facet normal 0 0 1\n    outer loop\n"
        for v in t:
            s += "      vertex %s %s %s\n" % v
        s += "    endloop\n  endfacet\n"
    return s + "endsolid %s\n" % name
def binary(tris, header=b"binary plane", count=None):
    b = header.ljust(80, b" ") + struct.pack("<I", len(tris) if count is None else count)
    for t in tris:
        b += struct.pack("<3f", 0, 0, 1) + b"".join(struct.pack("<3f", *v) for v in t) + b"\0\0"
    return b
def put(name, data):
    open("%s/%s" % (d, name), "wb").write(data if isinstance(data, bytes) else data.encode())
put("good.stl", ascii(tris))
put("good_bin.stl", binary(tris, b"solid plane, but binary"))
put("truncated.stl", binary(tris)[:-7])
put("count_more.stl", binary(tris, count=3))
put("count_less.stl", binary(tris, count=1))
put("nan_bin.stl", binary([tris[0], ((0, 0, 0), (1, float("nan"), 0), (0, 1, 0))]))
put("nan.stl", ascii(tris).replace("vertex 1 1 0", "vertex 1 nan 0", 1))
put("inf.stl", ascii(tris).replace("vertex 0 1 0", "vertex 0 1 -inf", 1))
put("keyword.stl", ascii(tris).replace("outer loop", "outer lop", 2).replace("outer lop", "outer loop", 1))
put("number.stl", ascii(tris).replace("vertex 1 0 0", "vertex 1 0,5 0", 1))
put("four.stl", ascii(tris).replace("    endloop", "      vertex 0 0 1\n    endloop", 1))
put("noend.stl", ascii(tris).replace("endsolid plane\n", ""))
put("solid_binary.stl", "solid x\n".encode() + binary(tris)[8:-3])
put("short.stl", b"\x01\x02\x03")
put("empty.stl", b"")
put("zero_count.stl", binary([]))
put("degenerate.stl", ascii([tris[0], ((0, 0, 0), (1, 1, 1), (2, 2, 2)), tris[1], ((1, 0, 0), (1, 0, 0), (0, 1, 0))]))
put("all_degenerate.stl", ascii([((0, 0, 0), (1, 1, 1), (2, 2, 2))]))
# (sparse files: no disk blocks)
with open("%s/huge.stl" % d, "wb") as f:
    f.write(binary(tris, count=2000000)[:84])
    f.truncate(84 + 50 * 2000000)
with open("%s/big.stl" % d, "wb") as f:
    f.write(b"solid big\n")
    f.truncate(300 * 1024 * 1024)
PY

# good files: ASCII, and binary whose header begins with "solid" (binary by its size)
scen good good.stl
expect ascii-ok 0 "mesh .*good.stl \(ASCII STL\), role bed: 2 triangles, x 0 to 1" check "$tmp/good.yaml"
scen goodb good_bin.stl
expect binary-solid-header-ok 0 "mesh .*good_bin.stl \(binary STL\), role bed: 2 triangles" check "$tmp/goodb.yaml"

# binary: truncated, the count against the size, NaN, no triangles, too many
scen trunc truncated.stl
expect truncated 2 "trunc.yaml:3:12: meshes.file: .*truncated.stl: truncated binary STL: it declares 2 triangles \(84 \+ 50 x 2 = 184 bytes\) but has 177 bytes; triangle index 1 is cut at byte offset 177" check "$tmp/trunc.yaml"
scen more count_more.stl
expect count-above-size 2 "count_more.stl: truncated binary STL: it declares 3 triangles \(84 \+ 50 x 3 = 234 bytes\) but has 184 bytes; triangle index 2 is cut at byte offset 184" check "$tmp/more.yaml"
scen less count_less.stl
expect count-below-size 2 "count_less.stl: binary STL declares 1 triangles \(84 \+ 50 x 1 = 134 bytes\) but has 184 bytes: 50 bytes after the last triangle, from byte offset 134" check "$tmp/less.yaml"
scen nanb nan_bin.stl
expect nan-binary 2 "nan_bin.stl: triangle index 1 \(byte offset 134\): vertex 2's y is not finite \(nan\)" check "$tmp/nanb.yaml"
scen zero zero_count.stl
expect zero-count 2 "zero_count.stl: binary STL with no triangles" check "$tmp/zero.yaml"
scen huge huge.stl
expect too-many 2 "huge.stl: binary STL of 2000000 triangles, more than the limit of 1000000" check "$tmp/huge.yaml"
scen big big.stl
expect too-big 2 "big.stl: 314572800 bytes, more than the limit of 268435456 for an STL file" check "$tmp/big.yaml"

# ASCII: NaN, Inf, a bad keyword, a bad number, a polygon, no endsolid, binary bytes
scen nan nan.stl
expect nan-ascii 2 "nan.yaml:3:12: meshes.file: .*nan.stl:6: vertex 3's y is not finite \(nan\)" check "$tmp/nan.yaml"
scen inf inf.stl
expect inf-ascii 2 "inf.stl:13: vertex 3's z is not finite \(-inf\)" check "$tmp/inf.yaml"
scen kw keyword.stl
expect bad-keyword 2 "keyword.stl:10: expected 'loop', found 'lop'" check "$tmp/kw.yaml"
scen num number.stl
expect bad-number 2 "number.stl:5: expected a number \(vertex 2's y\), found '0,5'" check "$tmp/num.yaml"
scen four four.stl
expect four-vertices 2 "four.stl:7: expected 'endloop', found 'vertex'" check "$tmp/four.yaml"
scen noend noend.stl
expect no-endsolid 2 "noend.stl:16: expected 'facet' or 'endsolid', found the end of the file" check "$tmp/noend.yaml"
scen sb solid_binary.stl
expect solid-but-binary 2 "solid_binary.stl:2: byte 0x[0-9a-f]{2} at byte offset [0-9]+ is not text: a binary STL whose size does not match its count" check "$tmp/sb.yaml"
scen short short.stl
expect short 2 "short.stl: neither ASCII STL \(it does not begin with 'solid'\) nor binary \(3 bytes" check "$tmp/short.yaml"
scen empty empty.stl
expect empty 2 "empty.stl: empty file" check "$tmp/empty.yaml"
scen missing nothing_here.stl
expect missing 2 "missing.yaml:3:12: meshes.file: .*nothing_here.stl: cannot open: No such file or directory" check "$tmp/missing.yaml"
scen dir .
expect directory 2 "missing|not a regular file" check "$tmp/dir.yaml"

# zero-area triangles: dropped with a warning (where the first was), the rest kept
scen degen degenerate.stl
expect degenerate-dropped 0 "warning: .*degenerate.stl: 2 triangles of zero area dropped \(the first at line 9\)" check "$tmp/degen.yaml"
grep -q "role bed: 2 triangles" "$tmp/out" && pass=$((pass + 1)) || { echo "FAIL degenerate: not 2 triangles kept"; fail=$((fail + 1)); }
scen alldeg all_degenerate.stl
expect all-degenerate 2 "all_degenerate.stl: every one of its 1 triangles has zero area" check "$tmp/alldeg.yaml"

# the entry's keys: a role, a scale, the extent of a scene, unknown keys
printf 'meshes:\n  - {file: good.stl, role: floor}\n' > "$tmp/role.yaml"
expect bad-role 2 "role.yaml:2:28: meshes.role: expected one of: bed, wall, dam" check "$tmp/role.yaml"
printf 'meshes:\n  - {file: good.stl}\n' > "$tmp/norole.yaml"
expect no-role 2 "norole.yaml:2:5: meshes: each mesh needs a role" check "$tmp/norole.yaml"
printf 'meshes:\n  - {file: good.stl, role: wall, scale: 1e5}\n' > "$tmp/far.yaml"
expect scale-range 2 "far.yaml:2:[0-9]+: meshes.scale: expected a number > 0 and <= 1e4" check "$tmp/far.yaml"
printf 'meshes:\n  - {file: good.stl, role: wall, scale: 1e4, translate: [5000, 0, 0]}\n' > "$tmp/far2.yaml"
expect beyond-extent 2 "far2.yaml:2:12: meshes: .*good.stl, line 2: a corner at \(15000, 0, 0\) m, beyond the 1e4 m" check "$tmp/far2.yaml"
printf 'meshes:\n  - {file: good.stl, role: wall, rotate: [0, 0, 1]}\n' > "$tmp/key.yaml"
expect unknown-key 2 "key.yaml:2:34: meshes: unknown key 'rotate' \(did you mean 'rotate_deg'\?\)" check "$tmp/key.yaml"
printf 'meshs:\n  - {file: good.stl, role: wall}\n' > "$tmp/sect.yaml"
expect unknown-section 2 "sect.yaml:1:1: unknown key 'meshs' \(did you mean 'meshes'\?\)" check "$tmp/sect.yaml"

# the flume without its flat bed
printf 'flume: {on: true, bed: false}\n' > "$tmp/nobed.yaml"
expect bed-off-roughness 2 "nobed.yaml:1:[0-9]+: flume.bed = false leaves the bed roughness without its bed" check "$tmp/nobed.yaml"
printf 'flume: {on: true, bed: false, roughness: false}\n' > "$tmp/nobed2.yaml"
expect bed-off-no-mesh 2 "nobed2.yaml:1:[0-9]+: flume.bed = false needs a mesh with role: bed" check "$tmp/nobed2.yaml"
# a mesh in the flume's packing box
printf 'flume: {on: true}\nspheres: {counts: [1, 1, 1, 1]}\nmeshes:\n  - {file: good.stl, role: wall, scale: 0.1, translate: [0.1, 0.1, 0.2]}\n' > "$tmp/inbox.yaml"
expect mesh-in-packing-box 2 "inbox.yaml:4: meshes: .*good.stl: its triangle 0 reaches into the flume's packing box" check "$tmp/inbox.yaml"

# a bad mesh leaves no output directory
expect run-refused 2 "truncated binary STL" run "$tmp/trunc.yaml" -o "$tmp/trunc-out"
[ ! -e "$tmp/trunc-out" ] && pass=$((pass + 1)) || { echo "FAIL a refused mesh left an output directory"; fail=$((fail + 1)); }

echo "mesh inputs: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
