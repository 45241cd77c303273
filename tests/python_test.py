#!/usr/bin/env python3
"""The Python package (python/sabodem) over the build's libsabodem.so: scenarios from files,
dicts and text with their errors, a run stepped phase by phase that ends in the same state, bit
for bit, as the program's run of the same scenario, the bodies as numpy arrays, and the worked
example (examples/design_study.py) in its reduced form.

    usage: SABODEM_LIBRARY=.../libsabodem.so PYTHONPATH=python python_test.py SABODEM_PROGRAM
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

import sabodem

SRC = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FLUME = os.path.join(SRC, "examples", "flume_small.yaml")
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL", what)


def main():
    program = sys.argv[1]
    tmp = tempfile.mkdtemp()
    version = subprocess.run([program, "--version"], capture_output=True, text=True).stdout.split()[1]
    check(sabodem.version() == version, f"version {sabodem.version()} != {version}")

    # errors: file:line:col, the key, the nearest key
    try:
        sabodem.Scenario.from_dict({"solver": {"dt": 1e-5, "durration": 1}})
        check(False, "a bad key was accepted")
    except sabodem.ScenarioError as e:
        check(str(e) == "<dict>:4:3: unknown key 'solver.durration' (did you mean 'solver.duration'?)", str(e))
    try:
        sabodem.Scenario.from_file(FLUME, set={"contact.k_n": -1})
        check(False, "a bad override was accepted")
    except sabodem.ScenarioError as e:
        check(str(e) == "--set:1:13: contact.k_n: must be > 0 and <= inf (N/m)", str(e))
    try:
        sabodem.Scenario.from_file(os.path.join(tmp, "none.yaml"))
        check(False, "a missing file was accepted")
    except sabodem.ScenarioError as e:
        check("none.yaml: cannot open" in str(e), str(e))

    # a scene from a dict: a sphere falls freely for 0.01 s (1000 steps)
    drop = sabodem.Scenario.from_dict({"solver": {"dt": 1e-5, "duration": 0.01}, "gravity": [0, 0, -9.81],
                                       "elements": [{"type": "sphere", "radius": 0.005, "position": [0, 0, 0.1]}]})
    with sabodem.Run(drop, os.path.join(tmp, "drop")) as r:
        check(r.phase == "run" and r.steps == 0, f"new run: {r.phase} {r.steps}")
        check(r.advance(0.004) and r.steps == 400, f"advance(0.004): {r.steps} steps")
        s = r.run()
        check(r.steps == 1000 and s["status"] == "finished" and s["steps"] == 1000, f"run: {r.steps}, {s['status']}")
        b = r.bodies()
        check(b["pos"].shape == (1, 3) and b["radius"].tolist() == [0.005], f"bodies {b['pos'].shape}")
        check(abs(b["pos"][0, 2] - (0.1 - 0.5 * 9.81 * 0.01 ** 2)) < 1e-6, f"free fall z {b['pos'][0, 2]}")
    check(json.load(open(os.path.join(tmp, "drop", "summary.json")))["steps"] == 1000, "drop summary.json")

    # the flume, phase by phase: the same end state as `sabodem run` of the same scenario
    over = {"phases.capture_limit": 0.05, "output.vtk": False, "output.png": False}
    argv = [program, "run", FLUME, "-o", os.path.join(tmp, "cli")]
    for k, v in over.items():
        argv += ["--set", f"{k}={str(v).lower()}"]
    subprocess.run(argv, check=True, capture_output=True)
    cli = json.load(open(os.path.join(tmp, "cli", "summary.json")))
    scenario = sabodem.Scenario.from_file(FLUME, set=over)
    with sabodem.Run(scenario, os.path.join(tmp, "py")) as r:
        b = r.bodies()
        moving = b["fixed"] == 0
        check(len(b["gid"]) == 756 and int(moving.sum()) == 186, f"flume bodies {len(b['gid'])}, moving {moving.sum()}")
        check(int(np.sum(b["shape"] == 1)) == 6 and np.all(b["half_length"][b["shape"] == 1] == 0.05), "six logs")
        check(sorted(set(b["radius"][moving & (b["shape"] == 0)].tolist())) == [0.005, 0.0075, 0.01], "sphere radii")
        phases = []
        while r.advance_phase():
            phases.append((r.phase, r.time))
        check([p for p, _ in phases] == ["flow", "capture", "done"], f"phases {phases}")
        check(abs(phases[0][1] - cli["phase_end_s"]["packing"]) < 5e-6 and abs(phases[1][1] - cli["phase_end_s"]["flow"]) < 5e-6,
              f"phase ends {phases}, the program's {cli['phase_end_s']}")
        s = r.finish()
    check(s["state_hash"] == cli["state_hash"] and s["steps"] == cli["steps"],
          f"stepped from Python {s['state_hash']} ({s['steps']} steps) != program {cli['state_hash']} ({cli['steps']})")
    check(s["trap_ratio"] == cli["trap_ratio"] and s["pipes"] == cli["pipes"], "trap ratio and pipes as the program's")

    # the worked example, reduced
    out = subprocess.run([sys.executable, os.path.join(SRC, "examples", "design_study.py"), "--quick",
                          os.path.join(tmp, "study")], capture_output=True, text=True)
    lines = out.stdout.splitlines()
    check(out.returncode == 0 and len(lines) == 3 and lines[1].startswith("narrow") and lines[2].startswith("wide"),
          f"design_study: {out.returncode} {out.stdout} {out.stderr}")

    print(f"python: {len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
