#!/usr/bin/env python3
"""Draw a scenario's design before it runs (`sabodem check FILE --png OUT.png`).

Usage: plot_design.py DATA_DIR OUT.png

DATA_DIR holds what `sabodem check` wrote: design.csv (key,value), members.csv (kind,axis_m)
and bodies.csv (the built scene). Two panels:
- front view of the dam (looking downstream): the flume section (bed, walls), the columns and
  beams to scale with their clear gaps in mm, and the largest boulder and a log drawn to scale
  in the lowest opening;
- side view of the initial state (flume frame, x along the bed): the bed roughness, the
  released spheres and logs, the gate and the dam.
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import EllipseCollection, LineCollection  # noqa: E402
from matplotlib.patches import Circle, Rectangle  # noqa: E402


def read_design(d):
    with open(os.path.join(d, "design.csv")) as f:
        return {r["key"]: float(r["value"]) for r in csv.DictReader(f)}


def read_members(d):
    cols, beams = [], []
    with open(os.path.join(d, "members.csv")) as f:
        for r in csv.DictReader(f):
            (cols if r["kind"] == "column" else beams).append(float(r["axis_m"]))
    return cols, sorted(beams)


def read_bodies(d):
    with open(os.path.join(d, "bodies.csv")) as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


def front_view(ax, g, cols, beams):
    mm = 1e3
    w, hw, dp = g["width"] * mm, g["wall_height"] * mm, g["pipe_diameter"] * mm
    ax.plot([0, 0, w, w], [hw, 0, 0, hw], color="k", lw=2)
    top = (beams[-1] + 0.5 * g["pipe_diameter"]) * mm if beams else hw
    for y in cols:
        ax.add_patch(Rectangle((y * mm - dp / 2, 0), dp, top, color="0.35"))
    for z in beams:
        ax.add_patch(Rectangle((0, z * mm - dp / 2), w, dp, color="0.35"))
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
    ax.set_title(f"dam, looking downstream: {len(cols)} column(s), {len(beams)} beam(s), pipes {dp:.0f} mm; "
                 f"boulder {dmax:.0f} mm", fontsize=9)


def side_view(ax, g, cols, beams, bodies):
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
        top = beams[-1] + dp / 2 if beams else hw
        ax.add_patch(Rectangle((g["x_dam"], 0), dp, top, color="0.35"))
        ax.text(g["x_dam"], top, " dam", fontsize=7, va="bottom")
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
    cols, beams = read_members(d)
    bodies = read_bodies(d)
    if not g.get("flume"):
        sys.exit("plot_design.py: not a flume scenario: nothing to draw")
    fig, (a, b) = plt.subplots(2, 1, figsize=(10, 9), gridspec_kw={"height_ratios": [1.4, 1]})
    front_view(a, g, cols, beams)
    side_view(b, g, cols, beams, bodies)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print("design drawn:", out)


if __name__ == "__main__":
    main()
