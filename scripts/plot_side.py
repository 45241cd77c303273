#!/usr/bin/python3
"""Side view (x-z in the flume frame) of one sabodem snapshot, written as a PNG.

Reads the .vtp files written by src/io_vtk.c with xml.etree (through check_vtk.read_vtp, no
VTK package): spheres are drawn as circles of their radius, cylinders (logs, and dam pipes
from a log-like .vtp) as their exact x-z silhouette (convex hull of the two projected end
circles). Dam pipes can also be given on the command line.

Examples:
  /usr/bin/python3 scripts/plot_side.py --spheres out/spheres_000120.vtp \\
      --logs out/logs_000120.vtp --pipes out/pipes.vtp --xmin 3.5 --xmax 4.1 --out side.png
  /usr/bin/python3 scripts/plot_side.py --spheres s.vtp --column 4.009,0.009,0.2 \\
      --beam 4.009,0.049,0.009 --xdam 4.0 --h 0.03 --out side.png

Options --ymin/--ymax keep only elements whose centre lies in that slab across the flume.
Uses Debian's python3-matplotlib with the Agg backend (no display needed).
"""
import argparse
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PatchCollection  # noqa: E402
from matplotlib.patches import Circle, Polygon  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_vtk import Fail, read_vtp  # noqa: E402

SPHERE_COLORS = ["#7f7f7f", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2"]


PIPE_TAG = 300


def load(path, need):
    """Return (centres Nx3, dict of point-data arrays as numpy, reshaped to N x ncomp)."""
    try:
        info = read_vtp(path)
    except Fail as e:
        sys.exit(f"plot_side: {e}")
    n = info["points"]
    pts = np.asarray(info["coords"], dtype=float).reshape(n, 3)
    arrays = {}
    for name, (nc, vals) in info["point_data"].items():
        a = np.asarray(vals, dtype=float)
        arrays[name] = a.reshape(n, nc) if nc > 1 else a
    for name in need:
        if name not in arrays:
            sys.exit(f"plot_side: {path}: no point-data array {name!r}")
    return pts, arrays


def hull(points):
    """Convex hull (monotone chain) of an Mx2 array, counter-clockwise."""
    pts = sorted(set(map(tuple, np.round(points, 12))))
    if len(pts) <= 2:
        return np.asarray(pts)

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.asarray(lower[:-1] + upper[:-1])


def cylinder_outline(c, a, length, r, nseg=24):
    """x-z silhouette polygon of a cylinder (centre c, unit axis a, full length, radius r)."""
    a = np.asarray(a, dtype=float)
    na = np.linalg.norm(a)
    a = a / na if na > 0 else np.array([0.0, 0.0, 1.0])
    t = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(a, t)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    ang = np.linspace(0.0, 2.0 * math.pi, nseg, endpoint=False)
    ring = r * (np.outer(np.cos(ang), e1) + np.outer(np.sin(ang), e2))
    ends = np.vstack([c + 0.5 * length * a + ring, c - 0.5 * length * a + ring])
    return hull(ends[:, [0, 2]])


def in_window(pts, ext, args):
    m = (pts[:, 0] + ext >= args.xmin) & (pts[:, 0] - ext <= args.xmax)
    if args.ymin is not None:
        m &= pts[:, 1] >= args.ymin
    if args.ymax is not None:
        m &= pts[:, 1] <= args.ymax
    return m


def triple(s, what):
    try:
        v = [float(x) for x in s.split(",")]
    except ValueError:
        v = []
    if len(v) != 3:
        raise argparse.ArgumentTypeError(f"{what}: expected three comma-separated numbers")
    return v


def main(argv=None):
    ap = argparse.ArgumentParser(description="x-z side view of a sabodem snapshot")
    ap.add_argument("--spheres", help="sphere .vtp (radius, optional tag)")
    ap.add_argument("--logs", help="cylinder .vtp of the logs (axis, length, radius)")
    ap.add_argument("--pipes", help="cylinder .vtp of the fixed dam pipes")
    ap.add_argument("--column", action="append", default=[], metavar="X,R,ZTOP",
                    type=lambda s: triple(s, "--column"),
                    help="vertical dam column: centre x, radius, top height (repeatable)")
    ap.add_argument("--beam", action="append", default=[], metavar="X,Z,R",
                    type=lambda s: triple(s, "--beam"),
                    help="horizontal dam beam across the flume: centre x, z, radius (repeatable)")
    ap.add_argument("--xmin", type=float, default=0.0)
    ap.add_argument("--xmax", type=float, default=4.35)
    ap.add_argument("--zmin", type=float, default=None, help="default: -0.02 m")
    ap.add_argument("--zmax", type=float, default=None, help="default: from the data")
    ap.add_argument("--ymin", type=float, default=None)
    ap.add_argument("--ymax", type=float, default=None)
    ap.add_argument("--xdam", type=float, default=None, help="draw the dam face at this x")
    ap.add_argument("--h", type=float, default=None, help="draw the flow surface z = h")
    ap.add_argument("--title", default=None)
    ap.add_argument("--width", type=float, default=12.0, help="figure width, inches")
    ap.add_argument("--dpi", type=int, default=150)
    ap.add_argument("--out", required=True, help="PNG to write")
    args = ap.parse_args(argv)
    if not args.xmax > args.xmin:
        ap.error("--xmax must exceed --xmin")

    patches_s, colors_s, patches_l, patches_p = [], [], [], []
    ztop = 0.0
    counts = {"spheres": 0, "logs": 0, "pipes": 0}

    if args.spheres:
        pts, arr = load(args.spheres, ["radius"])
        rad = arr["radius"]
        tag = arr.get("tag", np.zeros(len(rad)))
        m = in_window(pts, rad, args)
        for p, r, t in zip(pts[m], rad[m], tag[m]):
            patches_s.append(Circle((p[0], p[2]), r))
            colors_s.append(SPHERE_COLORS[int(t) % len(SPHERE_COLORS)])
            ztop = max(ztop, p[2] + r)
        counts["spheres"] = int(m.sum())

    for key, path in (("logs", args.logs), ("pipes", args.pipes)):
        if not path:
            continue
        pts, arr = load(path, ["axis", "length", "radius"])
        ext = 0.5 * arr["length"] + arr["radius"]
        # cylinders tagged 300 (sabodem's SD_TAG_PIPE) are fixed dam pipes, whichever file
        is_pipe = arr.get("tag", np.zeros(len(ext))) == PIPE_TAG
        if key == "pipes":
            is_pipe[:] = True
        m = in_window(pts, ext, args)
        for p, a, length, r, pipe in zip(pts[m], arr["axis"][m], arr["length"][m], arr["radius"][m], is_pipe[m]):
            poly = cylinder_outline(p, a, length, r)
            if len(poly) >= 3:
                (patches_p if pipe else patches_l).append(Polygon(poly, closed=True))
                if not pipe:
                    ztop = max(ztop, poly[:, 1].max())
        counts["pipes"] += int((m & is_pipe).sum())
        counts["logs"] += int((m & ~is_pipe).sum())

    for x, r, zt in args.column:
        patches_p.append(Polygon([(x - r, 0.0), (x + r, 0.0), (x + r, zt), (x - r, zt)], closed=True))
    for x, z, r in args.beam:
        patches_p.append(Circle((x, z), r))

    zmin = -0.02 if args.zmin is None else args.zmin
    zmax = args.zmax if args.zmax is not None else max(0.1, ztop + 0.02, (args.h or 0.0) + 0.02)
    if not zmax > zmin:
        ap.error("--zmax must exceed --zmin")
    span = args.xmax - args.xmin
    height = min(10.0, max(2.0, args.width * (zmax - zmin) / span + 0.8))
    fig, ax = plt.subplots(figsize=(args.width, height))
    ax.set_aspect("equal", adjustable="box" if height < 10.0 else "datalim")
    ax.axhspan(zmin, 0.0, color="#d9cbb0", zorder=0)  # below the bed
    ax.axhline(0.0, color="k", lw=0.8, zorder=1)
    if args.h is not None:
        ax.axhline(args.h, color="#4a90d9", lw=0.8, ls="--", zorder=1, label=f"h = {args.h:g} m")
    if args.xdam is not None:
        ax.axvline(args.xdam, color="r", lw=0.6, ls=":", zorder=1)
    if patches_s:
        ax.add_collection(PatchCollection(patches_s, facecolors=colors_s, edgecolors="k",
                                          linewidths=0.2, alpha=0.8, zorder=2))
    if patches_l:
        ax.add_collection(PatchCollection(patches_l, facecolors="#c8893e", edgecolors="#5a3a12",
                                          linewidths=0.4, alpha=0.9, zorder=3))
    if patches_p:
        ax.add_collection(PatchCollection(patches_p, facecolors="#555555", edgecolors="k",
                                          linewidths=0.4, alpha=0.55, zorder=4))
    ax.set_xlim(args.xmin, args.xmax)
    ax.set_ylim(zmin, zmax)
    ax.set_xlabel("x along the bed (m)")
    ax.set_ylabel("z normal to the bed (m)")
    title = args.title or os.path.basename(args.spheres or args.logs or args.pipes or "")
    ax.set_title(f"{title}  (spheres {counts['spheres']}, logs {counts['logs']}, "
                 f"pipes {counts['pipes'] + len(args.column) + len(args.beam)})", fontsize=9)
    if args.h is not None:
        ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    tmp = args.out + ".tmp.png"
    fig.savefig(tmp, dpi=args.dpi)
    plt.close(fig)
    os.replace(tmp, args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
