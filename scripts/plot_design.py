#!/usr/bin/env python3
"""Draw a scenario's design before it runs (`sabodem check FILE --png OUT.png`).

Usage: plot_design.py DATA_DIR OUT.png

DATA_DIR holds what `sabodem check` wrote: design.csv (key,value), members.csv (every pipe of
the dam: kind,axis_m,x0,y0,z0,x1,y1,z1,diameter_m) and bodies.csv (the built scene). Two panels:
- front view of the dam (looking downstream): the flume section (bed, walls), the columns and
  beams to scale with their clear gaps in mm, the members (dam.members) projected on the view,
  and the largest boulder and a log drawn to scale in the lowest opening;
- side view of the initial state (flume frame, x along the bed): the bed roughness, the
  released spheres and logs, the gate and the dam with its members projected.
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import EllipseCollection, LineCollection  # noqa: E402
from matplotlib.patches import Circle, Ellipse, Polygon, Rectangle  # noqa: E402


def read_design(d):
    with open(os.path.join(d, "design.csv")) as f:
        return {r["key"]: float(r["value"]) for r in csv.DictReader(f)}


def read_members(d):
    """The grid's column axes y and beam axes z (ascending), the columns' top, and the other
    members as (end, end, diameter) with each end (x, y, z)."""
    cols, beams, tops, members = [], [], [], []
    with open(os.path.join(d, "members.csv")) as f:
        for r in csv.DictReader(f):
            ends = (tuple(float(r[k]) for k in ("x0", "y0", "z0")), tuple(float(r[k]) for k in ("x1", "y1", "z1")))
            if r["kind"] == "column":
                cols.append(float(r["axis_m"]))
                tops.append(ends[1][2])
            elif r["kind"] == "beam":
                beams.append(float(r["axis_m"]))
            else:
                members.append((ends[0], ends[1], float(r["diameter_m"])))
    return cols, sorted(beams), (max(tops) if tops else None), members


def draw_pipe(ax, p0, p1, dia, u, v, scale, **style):
    """A flat-ended pipe with axis p0-p1 seen along the axis not in (u, v): the hull of its two
    end disks, each an ellipse of semi-axes r across the projected axis and r |a_view| along it."""
    w = 3 - u - v  # the view direction
    r = dia / 2
    L = sum((p1[i] - p0[i]) ** 2 for i in range(3)) ** 0.5
    a = [(p1[i] - p0[i]) / L for i in range(3)]
    q0, q1 = (p0[u] * scale, p0[v] * scale), (p1[u] * scale, p1[v] * scale)
    du, dv = q1[0] - q0[0], q1[1] - q0[1]
    lp = (du * du + dv * dv) ** 0.5
    if lp < 1e-9 * scale:  # along the view: a disk
        ax.add_patch(Circle(q0, r * scale, **style))
        return
    nu, nv = -dv / lp * r * scale, du / lp * r * scale
    ax.add_patch(Polygon([(q0[0] + nu, q0[1] + nv), (q1[0] + nu, q1[1] + nv), (q1[0] - nu, q1[1] - nv),
                          (q0[0] - nu, q0[1] - nv)], closed=True, **style))
    ang = math.degrees(math.atan2(dv, du))
    for q in (q0, q1):
        ax.add_patch(Ellipse(q, 2 * r * scale * abs(a[w]), 2 * r * scale, angle=ang, **style))


def read_bodies(d):
    with open(os.path.join(d, "bodies.csv")) as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


def front_view(ax, g, cols, beams, col_top, members):
    mm = 1e3
    w, hw, dp = g["width"] * mm, g["wall_height"] * mm, g["pipe_diameter"] * mm
    ax.plot([0, 0, w, w], [hw, 0, 0, hw], color="k", lw=2)
    top = col_top * mm if col_top is not None else (beams[-1] + 0.5 * g["pipe_diameter"]) * mm if beams else 0.0
    for p0, p1, dia in members:
        top = max(top, max(p0[2], p1[2]) * mm + dia / 2 * mm)
    for y in cols:
        ax.add_patch(Rectangle((y * mm - dp / 2, 0), dp, col_top * mm, color="0.35"))
    for z in beams:
        ax.add_patch(Rectangle((0, z * mm - dp / 2), w, dp, color="0.35"))
    for p0, p1, dia in members:  # projected on the y-z plane: y across, z up
        draw_pipe(ax, p0, p1, dia, 1, 2, mm, color="tab:purple", alpha=0.75)
    # clear gaps across at mid-height of the lowest opening, and up beside the first column
    edges_y = [0.0] + [e for y in sorted(cols) for e in (y * mm - dp / 2, y * mm + dp / 2)] + [w]
    z_lab = (beams[0] * mm - dp / 2) / 2 if beams else hw / 2
    for a, b in zip(edges_y[0::2], edges_y[1::2]):
        ax.annotate("", (a, z_lab), (b, z_lab), arrowprops=dict(arrowstyle="<->", lw=0.6, color="tab:blue"))
        ax.text((a + b) / 2, z_lab + 1.5, f"{b - a:.0f}", ha="center", va="bottom", fontsize=7, color="tab:blue")
    edges_z = [0.0] + [e for z in beams for e in (z * mm - dp / 2, z * mm + dp / 2)]
    y_lab = w + 4
    for a, b in zip(edges_z[0::2], edges_z[1::2]):
        ax.annotate("", (y_lab, a), (y_lab, b), arrowprops=dict(arrowstyle="<->", lw=0.6, color="tab:blue"))
        ax.text(y_lab + 2, (a + b) / 2, f"{b - a:.0f}", va="center", fontsize=7, color="tab:blue")
    # the largest boulder and a log, to scale, in the lowest opening between the first two members
    dmax = g["d_max"] * mm
    x0, x1 = max(zip(edges_y[0::2], edges_y[1::2]), key=lambda e: e[1] - e[0])  # the widest opening
    if dmax > 0:
        ax.add_patch(Circle(((x0 + x1) / 2, dmax / 2), dmax / 2, color="tab:brown", alpha=0.8))
    if g.get("logs", 0) > 0:
        L, d = g["log_length"] * mm, g["log_diameter"] * mm
        zl = (beams[0] * mm + dp / 2 + 5) if len(beams) > 1 else top + 10
        ax.add_patch(Rectangle((w / 2 - L / 2, zl), L, d, color="tab:olive", alpha=0.8))
        ax.text(w / 2, zl + d + 1, f"log {L:.0f} x {d:.0f}", ha="center", va="bottom", fontsize=7)
    ax.set_aspect("equal")
    ax.set_xlim(-10, w + 30)
    ax.set_ylim(-10, min(hw, max(1.6 * top, top + 40)) + 10)  # the walls go on up to their top
    ax.set_xlabel("y across the flume (mm)")
    ax.set_ylabel("z above the bed (mm)")
    more = f", {len(members)} member(s)" if members else ""
    ax.set_title(f"dam, looking downstream: {len(cols)} column(s), {len(beams)} beam(s){more}, pipes {dp:.0f} mm; "
                 f"boulder {dmax:.0f} mm", fontsize=9)


def side_view(ax, g, cols, beams, col_top, members, bodies):
    x, z, s = [], [], []
    segs = []
    fixed_x, fixed_z, fixed_s = [], [], []
    for b in bodies:
        if b["tag"] >= 300 and b["tag"] < 400:  # dam pipes: drawn from members.csv
            continue
        if b["half_length"] > 0:
            h = b["half_length"]
            segs.append([(b["x"] - h * b["ax"], b["z"] - h * b["az"]), (b["x"] + h * b["ax"], b["z"] + h * b["az"])])
        elif b["fixed"]:
            fixed_x.append(b["x"]), fixed_z.append(b["z"]), fixed_s.append(2 * b["radius"])
        else:
            x.append(b["x"]), z.append(b["z"]), s.append(2 * b["radius"])
    if fixed_x:
        ax.add_collection(EllipseCollection(fixed_s, fixed_s, 0, units="xy", offsets=list(zip(fixed_x, fixed_z)),
                                            transOffset=ax.transData, facecolors="0.6", edgecolors="none"))
    if x:
        ax.add_collection(EllipseCollection(s, s, 0, units="xy", offsets=list(zip(x, z)), transOffset=ax.transData,
                                            facecolors="tab:brown", edgecolors="none", alpha=0.7))
    if segs:
        ax.add_collection(LineCollection(segs, colors="tab:olive", linewidths=1.2))
    hw = g["wall_height"]
    ax.plot([0, g["x_end"]], [0, 0], color="k", lw=1.5)
    ax.plot([g["x_gate"]] * 2, [0, hw], color="tab:red", lw=1, ls="--")
    ax.text(g["x_gate"], hw, " gate", color="tab:red", fontsize=7, va="top")
    if cols or beams:
        dp = g["pipe_diameter"]
        top = col_top if col_top is not None else beams[-1] + dp / 2
        ax.add_patch(Rectangle((g["x_dam"], 0), dp, top, color="0.35"))
        ax.text(g["x_dam"], top, " dam", fontsize=7, va="bottom")
    for p0, p1, dia in members:  # projected on the x-z plane
        draw_pipe(ax, p0, p1, dia, 0, 2, 1.0, color="tab:purple", alpha=0.75)
    ax.set_aspect("equal")
    ax.set_xlim(-0.02, g["x_end"] + 0.02)
    ax.set_ylim(-0.02, hw + 0.02)
    ax.set_xlabel("x along the bed (m)")
    ax.set_ylabel("z (m)")
    ax.set_title(f"initial state (flume frame, slope {g['slope_deg']:.0f} deg)", fontsize=9)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    d, out = sys.argv[1], sys.argv[2]
    g = read_design(d)
    cols, beams, col_top, members = read_members(d)
    bodies = read_bodies(d)
    if not g.get("flume"):
        sys.exit("plot_design.py: not a flume scenario: nothing to draw")
    fig, (a, b) = plt.subplots(2, 1, figsize=(10, 9), gridspec_kw={"height_ratios": [1.4, 1]})
    front_view(a, g, cols, beams, col_top, members)
    side_view(b, g, cols, beams, col_top, members, bodies)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print("design drawn:", out)


if __name__ == "__main__":
    main()
