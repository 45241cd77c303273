#!/usr/bin/env python3
"""Summarise a sabodem sweep: cases.csv (mean and spread of every case) and figures.

usage: plot_sweep.py SWEEP_DIR

Reads SWEEP_DIR/results.csv (one row per run, written by `sabodem sweep`; columns in
docs/sweep.md), writes
SWEEP_DIR/cases.csv and, with matplotlib (Debian's python3-matplotlib, Agg backend):
  fig16_pv_vs_kw.png     trap ratio vs woody volume ratio K_w, at the l_V/d_max nearest 2.0 (Fig. 16)
  fig17_pv_vs_lv.png     trap ratio vs l_V/d_max, at the K_w nearest 5 % (Fig. 17)
  heatmap_pv.png         mean trap ratio over the first two varied keys
each run a point, the case mean a line, one line per value of the other varied keys (labelled
with them). K_w and l_V/d_max are each run's own (results.csv's k_w and l_v_d_max, from its
scenario's counts, sizes and dam), so the figures hold for any flume, not only the paper's.
A varied key's values are numbers, or text: the names of a set of variants (layout: narrow,
wide) or lists ([20, 40, 120]); text values keep the sweep file's order, on the heatmap's axes
and in the legends.
"""
import csv
import os
import statistics
import sys


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
    # each varied key's values in the order of the runs (the sweep file's), and whether they are numbers
    order = {k: {} for k in vary}
    for r in rows:
        for k in vary:
            order[k].setdefault(r[k], len(order[k]))

    def is_number(v):
        try:
            float(v)
            return True
        except ValueError:
            return False

    numeric = {k: all(is_number(v) for v in order[k]) for k in vary}

    def value_rank(k, v):
        """how a key's values sort: numbers by value, text in the sweep file's order"""
        return float(v) if numeric[k] else order[k][v]
    with open(os.path.join(d, "cases.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(vary + ["runs", "p_v_mean", "p_v_std", "p_v_min", "p_v_max", "p_v_logs_mean",
                           "v_held_mean_m3", "v_channel_mean_m3", "v_passed_mean_m3", "runs_cut_by_limit",
                           "peak_dam_force_mean_N", "wall_s_total"])
        for key, rs in sorted(cases.items(), key=lambda kv: [value_rank(k, v) for k, v in zip(vary, kv[0])]):
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

    def case_x(k, rs):
        """a case's x for key k: its runs' own K_w (%) or l_V/d_max for those keys, else the value
        (text values: their rank)"""
        if k in ("logs.count", "logs.k_w"):
            return round(100.0 * statistics.mean(float(r["k_w"]) for r in rs), 3)
        if k == "dam.l_v":
            return round(statistics.mean(float(r["l_v_d_max"]) for r in rs), 3)
        return value_rank(k, rs[0][k])

    def tick_labels(k, xs):
        if numeric[k] or k in ("logs.count", "logs.k_w", "dam.l_v"):
            return ["%.3g" % x for x in xs]
        names = {i: v for v, i in order[k].items()}
        return [names[x] for x in xs]

    def label(k):
        return {"logs.count": "woody volume ratio K_w (%)", "logs.k_w": "woody volume ratio K_w (%)",
                "dam.l_v": "l_V / d_max"}.get(k, k)

    def line_plot(xkey, fixed_key, fixed_x, fname, title):
        others = [k for k in vary if k not in (xkey, fixed_key)]
        groups = {}
        for key, rs in cases.items():
            if fixed_key and case_x(fixed_key, rs) != fixed_x:
                continue
            kv = dict(zip(vary, key))
            groups.setdefault(tuple(kv[k] for k in others), []).append((case_x(xkey, rs), rs))
        if not groups:
            return
        fig, ax = plt.subplots(figsize=(5.5, 4))
        for n, (g, members) in enumerate(sorted(groups.items(),
                                                key=lambda kv: [value_rank(k, v) for k, v in zip(others, kv[0])])):
            name = ", ".join(f"{k}={v}" for k, v in zip(others, g))
            xs = sorted(x for x, _ in members)
            ax.scatter([x for x, rs in members for _ in rs], [float(r["p_v"]) for _, rs in members for r in rs],
                       s=18, alpha=0.6, color=f"C{n % 10}")
            means = {x: statistics.mean(float(r["p_v"]) for r in rs) for x, rs in members}
            ax.plot(xs, [means[x] for x in xs], "-o", color=f"C{n % 10}", label=("mean " + name) if name else "mean")
        ax.set_xlabel(label(xkey))
        ax.set_ylabel("trap ratio P_V")
        ax.set_ylim(0, 1.05)
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(os.path.join(d, fname), dpi=120)
        plt.close(fig)

    def nearest(key, target):
        xs = sorted({case_x(key, rs) for rs in cases.values()})
        return min(xs, key=lambda x: abs(x - target))

    kw_key = next((k for k in vary if k in ("logs.count", "logs.k_w")), None)
    lv_key = next((k for k in vary if k == "dam.l_v"), None)
    if kw_key:
        lv = nearest(lv_key, 2.0) if lv_key else None
        line_plot(kw_key, lv_key, lv, "fig16_pv_vs_kw.png",
                  "Fig. 16 analogue" + (f": l_V/d_max = {lv:g}" if lv_key else ""))
    if lv_key:
        kw = nearest(kw_key, 5.0) if kw_key else None
        line_plot(lv_key, kw_key, kw, "fig17_pv_vs_lv.png",
                  "Fig. 17 analogue" + (f": K_w = {kw:g} %" if kw_key else ""))
    if len(vary) >= 2:
        a, b = vary[0], vary[1]
        xs = sorted({case_x(a, rs) for rs in cases.values()})
        ys = sorted({case_x(b, rs) for rs in cases.values()})
        cell = {}
        for rs in cases.values():  # (other varied keys, if any, averaged over)
            cell.setdefault((case_x(a, rs), case_x(b, rs)), []).extend(float(r["p_v"]) for r in rs)
        grid = [[statistics.mean(cell[(x, y)]) if (x, y) in cell else float("nan") for x in xs] for y in ys]
        fig, ax = plt.subplots(figsize=(5.5, 4))
        im = ax.imshow(grid, origin="lower", cmap="viridis", vmin=0, vmax=1, aspect="auto")
        ax.set_xticks(range(len(xs)), tick_labels(a, xs))
        ax.set_yticks(range(len(ys)), tick_labels(b, ys))
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
