#!/usr/bin/env python3
"""Summarise a sabodem sweep: cases.csv (mean and spread of every case) and figures.

usage: plot_sweep.py SWEEP_DIR

Reads SWEEP_DIR/results.csv (one row per run, written by `sabodem sweep`; columns in
docs/sweep.md), writes
SWEEP_DIR/cases.csv and, with matplotlib (Debian's python3-matplotlib, Agg backend):
  fig16_pv_vs_kw.png     trap ratio vs woody volume ratio K_w, at l_V/d_max = 2.0 (Fig. 16)
  fig17_pv_vs_lv.png     trap ratio vs l_V/d_max, at K_w = 5 % (Fig. 17)
  heatmap_pv.png         mean trap ratio over the whole matrix
each run a point, the case mean a line. Columns named logs.count are converted to K_w with
the sphere solid volume of SPEC §8 (4.748 L) and the log volume (phi 10 x 100 mm); dam.l_v
is converted to l_V/d_max with d_max = 20 mm, and l_V = 0 (no intermediate beam) is the
top beam's 118 mm (5.9).
"""
import csv
import math
import os
import statistics
import sys

V_SPHERES = 4.7479e-3
V_LOG = math.pi * 0.005 ** 2 * 0.1
D_MAX = 0.020
TOP_BEAM = 0.118


def kw_of(count):
    vt = float(count) * V_LOG
    return 100.0 * vt / (vt + V_SPHERES)


def lv_ratio(lv):
    lv = float(lv)
    return (lv if lv > 0 else TOP_BEAM) / D_MAX


def main():
    d = sys.argv[1]
    rows = list(csv.DictReader(open(os.path.join(d, "results.csv"))))
    if not rows:
        print("no finished runs")
        return 0
    cols = list(rows[0].keys())
    vary = cols[cols.index("seed") + 1:cols.index("p_v")]  # the varied keys sit between seed and p_v
    cases = {}
    for r in rows:
        key = tuple(r[k] for k in vary)
        cases.setdefault(key, []).append(r)
    with open(os.path.join(d, "cases.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(vary + ["runs", "p_v_mean", "p_v_std", "p_v_min", "p_v_max", "p_v_logs_mean",
                           "v_held_mean_m3", "v_channel_mean_m3", "v_passed_mean_m3", "runs_cut_by_limit",
                           "peak_dam_force_mean_N", "wall_s_total"])
        for key, rs in sorted(cases.items(), key=lambda kv: [float(x) for x in kv[0]]):
            pv = [float(r["p_v"]) for r in rs]
            w.writerow(list(key) + [len(rs), "%.5f" % statistics.mean(pv),
                                    "%.5f" % (statistics.stdev(pv) if len(pv) > 1 else 0.0),
                                    "%.5f" % min(pv), "%.5f" % max(pv),
                                    "%.5f" % statistics.mean(float(r["p_v_logs"]) for r in rs),
                                    "%.4e" % statistics.mean(float(r["v_held_m3"]) for r in rs),
                                    "%.4e" % statistics.mean(float(r["v_channel_m3"]) for r in rs),
                                    "%.4e" % statistics.mean(float(r["v_passed_m3"]) for r in rs),
                                    sum(r["capture_end"] == "limit" for r in rs),
                                    "%.4e" % statistics.mean(float(r["peak_dam_force_N"]) for r in rs),
                                    "%.1f" % sum(float(r["wall_s"]) for r in rs)])
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def xval(k, v):
        if k == "logs.count":
            return kw_of(v)
        if k == "logs.k_w":
            return 100.0 * float(v)
        if k == "dam.l_v":
            return lv_ratio(v)
        return float(v)

    def label(k):
        return {"logs.count": "woody volume ratio K_w (%)", "logs.k_w": "woody volume ratio K_w (%)",
                "dam.l_v": "l_V / d_max"}.get(k, k)

    def line_plot(xkey, fixed_key, fixed_pick, fname, title):
        pts, means = [], {}
        for key, rs in cases.items():
            kv = dict(zip(vary, key))
            if fixed_key and fixed_key in kv and not fixed_pick(kv[fixed_key]):
                continue
            x = xval(xkey, kv[xkey])
            for r in rs:
                pts.append((x, float(r["p_v"])))
            means[x] = statistics.mean(float(r["p_v"]) for r in rs)
        if not pts:
            return
        fig, ax = plt.subplots(figsize=(5, 4))
        ax.scatter([p[0] for p in pts], [p[1] for p in pts], s=18, alpha=0.7, label="runs")
        xs = sorted(means)
        ax.plot(xs, [means[x] for x in xs], "-o", color="C3", label="mean")
        ax.set_xlabel(label(xkey))
        ax.set_ylabel("trap ratio P_V")
        ax.set_ylim(0, 1.05)
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(d, fname), dpi=120)
        plt.close(fig)

    kw_key = next((k for k in vary if k in ("logs.count", "logs.k_w")), None)
    lv_key = next((k for k in vary if k == "dam.l_v"), None)
    if kw_key:
        pick = (lambda v: abs(lv_ratio(v) - 2.0) < 1e-6) if lv_key else None
        line_plot(kw_key, lv_key, pick, "fig16_pv_vs_kw.png", "Fig. 16 analogue: l_V/d_max = 2.0")
    if lv_key:
        pick = None
        if kw_key:
            kws = sorted({xval(kw_key, dict(zip(vary, k))[kw_key]) for k in cases})
            target = min(kws, key=lambda x: abs(x - 5.0))
            pick = lambda v: abs(xval(kw_key, v) - target) < 1e-9
        line_plot(lv_key, kw_key, pick, "fig17_pv_vs_lv.png", "Fig. 17 analogue: K_w = 5 %")
    if len(vary) >= 2:
        a, b = vary[0], vary[1]
        xs = sorted({xval(a, k[0]) for k in cases})
        ys = sorted({xval(b, k[1]) for k in cases})
        grid = [[float("nan")] * len(xs) for _ in ys]
        for key, rs in cases.items():
            grid[ys.index(xval(b, key[1]))][xs.index(xval(a, key[0]))] = statistics.mean(float(r["p_v"]) for r in rs)
        fig, ax = plt.subplots(figsize=(5.5, 4))
        im = ax.imshow(grid, origin="lower", cmap="viridis", vmin=0, vmax=1, aspect="auto")
        ax.set_xticks(range(len(xs)), ["%.3g" % x for x in xs])
        ax.set_yticks(range(len(ys)), ["%.3g" % y for y in ys])
        for j, row in enumerate(grid):
            for i, v in enumerate(row):
                if v == v:
                    ax.text(i, j, "%.2f" % v, ha="center", va="center", color="w", fontsize=8)
        ax.set_xlabel(label(a))
        ax.set_ylabel(label(b))
        fig.colorbar(im, label="mean P_V")
        fig.tight_layout()
        fig.savefig(os.path.join(d, "heatmap_pv.png"), dpi=120)
        plt.close(fig)
    print("cases.csv and figures written to", d)
    return 0


if __name__ == "__main__":
    sys.exit(main())
