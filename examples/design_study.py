#!/usr/bin/env python3
"""A design study from Python: two grid dams on the reduced flume (examples/flume_small.yaml),
the same debris, three seeds each. For each dam: the trap ratio P_V, what reached the dam, and
the largest force on a pipe. About a minute on two cores.

    PYTHONPATH=python SABODEM_LIBRARY=build/libsabodem.so python3 examples/design_study.py [OUTDIR]
    (installed: python3 examples/design_study.py; --quick: one seed, a short capture)
"""
import os
import statistics
import sys

import numpy as np

import sabodem

HERE = os.path.dirname(os.path.abspath(__file__))
# the two designs: the flume's own dam (columns 35 mm apart) and one with wider openings and no
# intermediate beam
DAMS = {
    "narrow": {"dam.l_h": 0.035, "dam.l_v": 0.040},
    "wide": {"dam.l_h": 0.060, "dam.l_v": 0.0},
}


def one_run(outdir, dam, seed, quick):
    settings = dict(dam, **{"solver.seed": seed, "output.vtk": False, "output.png": False})
    if quick:
        settings["phases.capture_limit"] = 0.05
    scenario = sabodem.Scenario.from_file(os.path.join(HERE, "flume_small.yaml"), set=settings)
    with sabodem.Run(scenario, outdir) as run:
        # step phase by phase; at the end of the flow (the front at the dam) look at the debris
        while run.phase != "capture" and run.advance_phase():
            pass
        b = run.bodies()
        moving = b["fixed"] == 0
        logs = int(np.sum(moving & (b["shape"] == 1)))
        front = float(np.max(b["pos"][moving, 0] + b["radius"][moving]))
        summary = run.run()
    peak = max((p["peak_force_N"] for p in summary["pipes"]), default=0.0)
    return {"p_v": summary["trap_ratio"], "peak_N": peak, "logs": logs, "front_m": front,
            "hash": summary["state_hash"]}


def main():
    args = [a for a in sys.argv[1:] if a != "--quick"]
    quick = "--quick" in sys.argv[1:]
    outdir = args[0] if args else "out/design_study"
    seeds = [1] if quick else [1, 2, 3]
    print(f"sabodem {sabodem.version()}: {len(DAMS)} dams x {len(seeds)} seeds on flume_small")
    for name, dam in DAMS.items():
        runs = [one_run(os.path.join(outdir, f"{name}_seed{s}"), dam, s, quick) for s in seeds]
        pv = [r["p_v"] for r in runs]
        spread = statistics.stdev(pv) if len(pv) > 1 else 0.0
        print(f"{name:7s} l_h = {dam['dam.l_h'] * 1000:.0f} mm, l_v = {dam['dam.l_v'] * 1000:.0f} mm: "
              f"P_V = {statistics.mean(pv):.3f} +- {spread:.3f}, largest pipe force "
              f"{max(r['peak_N'] for r in runs):.2f} N, front at the dam {runs[0]['front_m']:.3f} m "
              f"with {runs[0]['logs']} logs")


if __name__ == "__main__":
    main()
