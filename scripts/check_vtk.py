#!/usr/bin/env python3
"""Independent checker for the VTK XML files sabodem writes (.vtp PolyData, .pvd collections).

Uses only the Python standard library (xml.etree), no VTK package, so it checks the files the
way a foreign reader would. ASCII data arrays only (what src/io_vtk.c writes).

Examples:
  python3 scripts/check_vtk.py out/spheres_000010.vtp --points 4619 --fields radius,velocity:3
  python3 scripts/check_vtk.py out/walls.vtp --polys 4 --cell-fields group,normal:3
  python3 scripts/check_vtk.py out/spheres.pvd --entries 2 --recurse
  python3 scripts/check_vtk.py out/logs.vtp --dump axis

Checks always made on a .vtp: root VTKFile type="PolyData"; every DataArray is ascii, parses
as numbers (finite), and holds tuples x components values matching its section (points, point
data, cell data); connectivity/offsets of Verts/Lines/Strips/Polys are consistent and index
existing points. On a .pvd: root type="Collection", every DataSet has a numeric timestep and a
file that exists (relative to the .pvd's directory; --no-files skips that).
Exit status 0 when every check passes, 1 otherwise (each failure printed as "FAIL: ...").
"""
import argparse
import math
import os
import sys
import xml.etree.ElementTree as ET

CELL_KINDS = ("Verts", "Lines", "Strips", "Polys")
INT_TYPES = ("Int8", "Int16", "Int32", "Int64", "UInt8", "UInt16", "UInt32", "UInt64")
FLOAT_TYPES = ("Float32", "Float64")


class Fail(Exception):
    pass


def parse_values(da, where):
    fmt = da.get("format", "ascii")
    if fmt != "ascii":
        raise Fail(f"{where}: DataArray format {fmt!r} not supported (ascii only)")
    typ = da.get("type")
    text = (da.text or "").split()
    try:
        if typ in INT_TYPES:
            vals = [int(t) for t in text]
        elif typ in FLOAT_TYPES:
            vals = [float(t) for t in text]
            bad = [v for v in vals if not math.isfinite(v)]
            if bad:
                raise Fail(f"{where}: {len(bad)} non-finite values")
        else:
            raise Fail(f"{where}: unknown DataArray type {typ!r}")
    except ValueError as e:
        raise Fail(f"{where}: unparsable value ({e})")
    return vals


def read_arrays(section, ntuples, label):
    """Name -> (ncomp, values) for the DataArrays of a PointData/CellData section."""
    out = {}
    if section is None:
        return out
    for da in section.findall("DataArray"):
        name = da.get("Name")
        if not name:
            raise Fail(f"{label}: DataArray without Name")
        ncomp = int(da.get("NumberOfComponents", "1"))
        vals = parse_values(da, f"{label}/{name}")
        if len(vals) != ntuples * ncomp:
            raise Fail(f"{label}/{name}: {len(vals)} values, expected {ntuples} x {ncomp}")
        if name in out:
            raise Fail(f"{label}: duplicate array {name!r}")
        out[name] = (ncomp, vals)
    return out


def read_vtp(path):
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise Fail(f"{path}: not well-formed XML ({e})")
    if root.tag != "VTKFile" or root.get("type") != "PolyData":
        raise Fail(f"{path}: not a VTKFile of type PolyData")
    poly = root.find("PolyData")
    if poly is None:
        raise Fail(f"{path}: no PolyData element")
    pieces = poly.findall("Piece")
    if not pieces:
        raise Fail(f"{path}: no Piece")
    info = {"points": 0, "Verts": 0, "Lines": 0, "Strips": 0, "Polys": 0,
            "point_data": {}, "cell_data": {}, "coords": []}
    for k, pc in enumerate(pieces):
        lab = f"{path}:Piece[{k}]"
        npts = int(pc.get("NumberOfPoints", "0"))
        ncells = {c: int(pc.get("NumberOf" + c, "0")) for c in CELL_KINDS}
        pts = pc.find("Points")
        if npts > 0 or pts is not None:
            if pts is None or pts.find("DataArray") is None:
                raise Fail(f"{lab}: no Points array")
            da = pts.find("DataArray")
            if int(da.get("NumberOfComponents", "1")) != 3:
                raise Fail(f"{lab}: Points must have 3 components")
            xyz = parse_values(da, lab + "/Points")
            if len(xyz) != 3 * npts:
                raise Fail(f"{lab}: {len(xyz)} point coordinates, expected 3 x {npts}")
            info["coords"].extend(xyz)
        for c in CELL_KINDS:
            el = pc.find(c)
            if ncells[c] == 0 and el is None:
                continue
            if el is None:
                raise Fail(f"{lab}: NumberOf{c}={ncells[c]} but no <{c}>")
            arrs = {da.get("Name"): da for da in el.findall("DataArray")}
            if "connectivity" not in arrs or "offsets" not in arrs:
                raise Fail(f"{lab}/{c}: needs connectivity and offsets")
            conn = parse_values(arrs["connectivity"], f"{lab}/{c}/connectivity")
            offs = parse_values(arrs["offsets"], f"{lab}/{c}/offsets")
            if len(offs) != ncells[c]:
                raise Fail(f"{lab}/{c}: {len(offs)} offsets, expected {ncells[c]}")
            prev = 0
            for o in offs:
                if o <= prev:
                    raise Fail(f"{lab}/{c}: offsets not increasing")
                prev = o
            if (offs[-1] if offs else 0) != len(conn):
                raise Fail(f"{lab}/{c}: last offset {offs[-1] if offs else 0} != {len(conn)}")
            if any(i < 0 or i >= npts for i in conn):
                raise Fail(f"{lab}/{c}: connectivity indexes a missing point")
            if c == "Polys" and any(b - a < 3 for a, b in zip([0] + offs[:-1], offs)):
                raise Fail(f"{lab}/Polys: polygon with fewer than 3 points")
        pd = read_arrays(pc.find("PointData"), npts, lab + "/PointData")
        cd = read_arrays(pc.find("CellData"), sum(ncells.values()), lab + "/CellData")
        for dst, src in (("point_data", pd), ("cell_data", cd)):
            for name, (nc, vals) in src.items():
                if name in info[dst] and info[dst][name][0] != nc:
                    raise Fail(f"{lab}: array {name!r} changes components between pieces")
                info[dst].setdefault(name, (nc, []))[1].extend(vals)
        info["points"] += npts
        for c in CELL_KINDS:
            info[c] += ncells[c]
    return info


def read_pvd(path, check_files):
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise Fail(f"{path}: not well-formed XML ({e})")
    if root.tag != "VTKFile" or root.get("type") != "Collection":
        raise Fail(f"{path}: not a VTKFile of type Collection")
    coll = root.find("Collection")
    if coll is None:
        raise Fail(f"{path}: no Collection element")
    entries = []
    base = os.path.dirname(os.path.abspath(path))
    for k, ds in enumerate(coll.findall("DataSet")):
        f = ds.get("file")
        if not f:
            raise Fail(f"{path}: DataSet[{k}] without file")
        try:
            t = float(ds.get("timestep", "0"))
        except ValueError:
            raise Fail(f"{path}: DataSet[{k}] timestep not a number")
        full = f if os.path.isabs(f) else os.path.join(base, f)
        if check_files and not os.path.isfile(full):
            raise Fail(f"{path}: DataSet[{k}] file {f!r} does not exist")
        entries.append((t, int(ds.get("part", "0") or 0), f, full))
    return entries


def parse_fields(spec):
    """'radius,velocity:3' -> [('radius', None), ('velocity', 3)]"""
    out = []
    for item in filter(None, (s.strip() for s in (spec or "").split(","))):
        name, _, nc = item.partition(":")
        out.append((name, int(nc) if nc else None))
    return out


def check_fields(arrays, wanted, kind, fails):
    for name, nc in wanted:
        if name not in arrays:
            fails.append(f"{kind} field {name!r} missing (have {sorted(arrays)})")
        elif nc is not None and arrays[name][0] != nc:
            fails.append(f"{kind} field {name!r} has {arrays[name][0]} components, expected {nc}")


def summary_vtp(path, info):
    fmt = lambda d: ", ".join(f"{k}({v[0]})" for k, v in d.items())
    return (f"{path}: PolyData points={info['points']} verts={info['Verts']} "
            f"lines={info['Lines']} polys={info['Polys']} "
            f"point_data=[{fmt(info['point_data'])}] cell_data=[{fmt(info['cell_data'])}]")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("file")
    ap.add_argument("--points", type=int, help="expected number of points")
    ap.add_argument("--verts", type=int, help="expected number of vertex cells")
    ap.add_argument("--polys", type=int, help="expected number of polygons")
    ap.add_argument("--fields", help="point-data arrays that must exist: name[:ncomp],...")
    ap.add_argument("--cell-fields", help="cell-data arrays that must exist: name[:ncomp],...")
    ap.add_argument("--entries", type=int, help="(.pvd) expected number of DataSet entries")
    ap.add_argument("--recurse", action="store_true", help="(.pvd) also check every listed .vtp")
    ap.add_argument("--no-files", action="store_true", help="(.pvd) do not require listed files")
    ap.add_argument("--dump", metavar="NAME",
                    help="print array NAME (point or cell data, or 'Points'), one tuple a line")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)

    fails = []
    try:
        if not os.path.isfile(a.file):
            raise Fail(f"{a.file}: no such file")
        with open(a.file, "rb") as fh:
            head = fh.read(400)
        is_pvd = b'type="Collection"' in head or a.file.endswith(".pvd")
        if is_pvd:
            entries = read_pvd(a.file, not a.no_files)
            if not a.quiet:
                print(f"{a.file}: Collection entries={len(entries)} "
                      f"times={[e[0] for e in entries]}")
                for t, part, f, _ in entries:
                    print(f"  t={t:.9g} part={part} file={f}")
            if a.entries is not None and len(entries) != a.entries:
                fails.append(f"{len(entries)} entries, expected {a.entries}")
            if a.recurse:
                for _, _, f, full in entries:
                    try:
                        info = read_vtp(full)
                        if not a.quiet:
                            print("  " + summary_vtp(f, info))
                    except Fail as e:
                        fails.append(str(e))
            for opt in ("points", "verts", "polys", "fields", "cell_fields", "dump"):
                if getattr(a, opt) is not None:
                    fails.append(f"--{opt.replace('_', '-')} applies to .vtp files, not .pvd")
        else:
            info = read_vtp(a.file)
            if not a.quiet:
                print(summary_vtp(a.file, info))
            if a.points is not None and info["points"] != a.points:
                fails.append(f"{info['points']} points, expected {a.points}")
            if a.verts is not None and info["Verts"] != a.verts:
                fails.append(f"{info['Verts']} verts, expected {a.verts}")
            if a.polys is not None and info["Polys"] != a.polys:
                fails.append(f"{info['Polys']} polys, expected {a.polys}")
            check_fields(info["point_data"], parse_fields(a.fields), "point-data", fails)
            check_fields(info["cell_data"], parse_fields(a.cell_fields), "cell-data", fails)
            if a.entries is not None:
                fails.append("--entries applies to .pvd files")
            if a.dump:
                if a.dump == "Points":
                    nc, vals = 3, info["coords"]
                else:
                    arr = info["point_data"].get(a.dump) or info["cell_data"].get(a.dump)
                    if arr is None:
                        raise Fail(f"--dump: no array {a.dump!r}")
                    nc, vals = arr
                for i in range(0, len(vals), nc):
                    print(" ".join(repr(v) for v in vals[i:i + nc]))
    except Fail as e:
        fails.append(str(e))
    for f in fails:
        print(f"FAIL: {f}", file=sys.stderr)
    if not fails and not a.quiet:
        print("OK")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
