#!/usr/bin/env python3
"""The architecture's rules (docs/architecture.md), checked on the sources and the compiled
objects: each file includes and calls only its own layer and those below; the driver and the
app reach the engine through include/sabodem.h alone; no two files call each other, directly or
round a loop. Exits 1 and names each breach.

    usage: check_layers.py SOURCE_DIR BUILD_DIR
"""
import collections
import glob
import os
import re
import subprocess
import sys

LAYERS = ["core", "geom", "engine", "driver", "app"]
DRIVER = {"scenario", "io_stl", "scene_report", "pipe_loads", "debris", "yaml_tree", "build", "run", "run_ctx", "run_output", "run_state", "run_dir", "run_api", "trap", "water", "fluid",
          "io_vtk", "sweep", "sweep_file", "sweep_identity", "scenario_cost", "scenario_materials", "slabs", "run_slabs"}


def layer_of(rel):
    """rel: a path under the source dir, e.g. src/core/hash.c, src/run.h, app/plot.c"""
    if rel.startswith("app/"):
        return "app"
    if rel == "include/sabodem_run.h":
        return "driver"
    if rel.startswith("src/core/") or rel == "include/sabodem.h":
        return "core"
    if rel.startswith("src/geom/"):
        return "geom"
    stem = os.path.splitext(os.path.basename(rel))[0]
    return "driver" if stem in DRIVER else "engine"


def public_symbols(src):
    text = open(os.path.join(src, "include/sabodem.h")).read()
    return set(re.findall(r"\b(sd_[a-z0-9_]+)\s*\(", text))


def includes(src, rel):
    out = []
    for line in open(os.path.join(src, rel), errors="replace"):
        m = re.match(r'\s*#\s*include\s+"([^"]+)"', line)
        if m:
            out.append(m.group(1))
    return out


def resolve(src, rel, inc):
    for base in (os.path.dirname(rel), "src", "include", "app"):
        cand = os.path.normpath(os.path.join(base, inc))
        if os.path.exists(os.path.join(src, cand)):
            return cand
    return None


def main():
    if len(sys.argv) != 3:
        print(__doc__)
        return 2
    src, build = sys.argv[1], sys.argv[2]
    bad = []
    files = [os.path.relpath(p, src) for p in glob.glob(os.path.join(src, "src/**/*.[ch]"), recursive=True)]
    files += [os.path.relpath(p, src) for p in glob.glob(os.path.join(src, "app/*.[ch]"))]
    # includes: down or sideways only; above the engine, no engine header but sabodem.h
    for rel in sorted(files):
        la = LAYERS.index(layer_of(rel))
        for inc in includes(src, rel):
            target = resolve(src, rel, inc)
            if target is None and os.path.exists(os.path.join(build, "generated", inc)):
                continue  # a header the build generates (the build id): data, of no layer
            if target is None:
                bad.append(f"{rel}: includes {inc}, which is not in the tree")
                continue
            lb = LAYERS.index(layer_of(target))
            if lb > la:
                bad.append(f"{rel} ({LAYERS[la]}) includes {target} ({LAYERS[lb]}), a higher layer")
            if la >= LAYERS.index("driver") and LAYERS[lb] == "engine":
                bad.append(f"{rel} ({LAYERS[la]}) includes the engine's {target}: the public API is include/sabodem.h")
    # calls, from the objects' symbols
    objs = glob.glob(os.path.join(build, "CMakeFiles/sabodem_lib.dir/src/**/*.o"), recursive=True)
    objs += glob.glob(os.path.join(build, "CMakeFiles/sabodem.dir/app/*.o"))
    if not objs:
        print(f"check_layers: no object files under {build}")
        return 2
    defs, uses = {}, collections.defaultdict(set)
    for o in objs:
        rel = os.path.relpath(o, build).split(".dir/", 1)[1][: -len(".o")]  # src/x.c or app/x.c
        for line in subprocess.run(["nm", o], capture_output=True, text=True, check=True).stdout.splitlines():
            p = line.split()
            if len(p) == 3 and p[1] in "TDBR":
                defs[p[2]] = rel
            elif len(p) == 2 and p[0] == "U":
                uses[rel].add(p[1])
    public = public_symbols(src)
    graph = collections.defaultdict(set)
    for a, syms in uses.items():
        la = LAYERS.index(layer_of(a))
        for sym in syms:
            b = defs.get(sym)
            if b is None or b == a:
                continue
            graph[a].add(b)
            lb = LAYERS.index(layer_of(b))
            if lb > la:
                bad.append(f"{a} ({LAYERS[la]}) calls {sym} of {b} ({LAYERS[lb]}), a higher layer")
            if la >= LAYERS.index("driver") and LAYERS[lb] == "engine" and sym not in public:
                bad.append(f"{a} ({LAYERS[la]}) calls {sym} of {b}, not in the public API")
    # loops: strongly connected components of more than one file
    index, low, stack, on, sccs, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                sccs.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in list(graph):
        if v not in index:
            visit(v)
    for comp in sccs:
        bad.append("files that call each other round a loop: " + ", ".join(comp))
    for b in bad:
        print("check_layers:", b)
    n_edges = sum(len(v) for v in graph.values())
    print(f"check_layers: {len(files)} sources, {len(objs)} objects, {n_edges} call edges, {len(bad)} breaches")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
