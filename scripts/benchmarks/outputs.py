"""The whole ``workspace`` command and its kernels against a per-pose scipy LP, in the same rounds.

For IPAnema 3 on a fine grid (by default 0.1, 0.1, 0.05 m) and for planar2:

1. the baseline: per-pose scipy ``linprog`` (HiGHS) feasibility of a fixed random sample of the
   grid's poses, in this process, scaled to the whole grid (feasibility only: no tensions, no
   margin, no file); timed before and after each round, each ratio taken within its round;
2. the kernels in this process: ``workspaces.run`` without maps or rows, warm; with ``--baseline``,
   also each checkout's kernels in a child process in the same rounds (:data:`KERNEL_CHILD`);
3. the whole command, ``cdpr-design workspace SPEC --json`` in a new process (start-up,
   spec, numba's start-up -- ``load_s`` --, sweep, ``workspace.csv``, pictures, summary, exit),
   with ``--format csv`` and ``parquet``, warm, and once from an empty numba cache; with
   ``--baseline``, the baseline checkout's command in the same rounds;
4. the fixed costs under any command (a process that only starts Python, imports numpy, calls
   one small cached kernel, imports matplotlib);
5. the CSV writer alone on IPAnema 3's rows: printf per row (the first writer), the numpy and
   the numba formatters.

Ratios: the LP's time for the grid / the measured time, wall clock and CPU.
"""

from __future__ import annotations

import re

import numpy as np
import yaml

from benchmarks import harness as h

OPTIONS = {"design": "ipanema3", "step": (0.1, 0.1, 0.05), "sample": 300, "formats": ("csv", "parquet"),
           "cold": True, "planar2": True, "planar2_step": 0.002, "floor": True, "writer_step": 0.14}
QUICK = {"step": 0.2, "sample": 100, "formats": ("csv",), "planar2_step": None, "floor": False, "writer_step": None}

#: The fixed costs under every command: what a process doing only this takes.
FLOOR = {
    "python start-up": "pass",
    "python, numpy": "import numpy",
    "python, numpy, numba, a small cached kernel's first call": (
        "import numpy as np; from cdpr_design.kernels.linalg import det_small; det_small(np.eye(2), 2)"),
    "python, the command's modules (no numba)": "import cdpr_design.cli.app, cdpr_design.jobs.workspace",
    "python, matplotlib.pyplot (the picture process)": "import matplotlib; matplotlib.use('Agg'); import matplotlib.pyplot",
}


def lp_poses(design, grid, count, rng) -> list[list[float]]:
    """A random sample of ``count`` poses of the grid (the LP baseline's poses)."""
    from cdpr_design.workspaces.grid import grid_positions

    idx = np.sort(rng.choice(grid.size, size=min(count, grid.size), replace=False))
    ori = list(design.workspace.orientation or [])
    return [list(grid_positions(grid, int(i), 1)[0]) + ori for i in idx]


def linprog_feasible(design, poses) -> int:
    """Per-pose scipy ``linprog`` (HiGHS) feasibility of ``poses``: how many are feasible."""
    from scipy.optimize import linprog

    from cdpr_design.statics import kinematics as kin

    bounds = list(zip(design.tension_min, design.tension_max))
    feasible = 0
    for pose in poses:
        res = linprog(np.zeros(design.m), A_eq=kin.structure_matrix(design, pose),
                      b_eq=kin.required_wrench(design, pose), bounds=bounds, method="highs")
        feasible += res.status == 0
    return feasible


def spec_file(b: h.Bench, root, name: str, step) -> tuple[str, list[str]]:
    """The spec path and ``--step`` arguments of the command for ``step`` (a number, or one per axis:
    then a copy of the spec with that grid step)."""
    path = root / "designs" / f"{name}.yaml"
    if step is None:
        return str(path), []
    if np.isscalar(step):
        return str(path), ["--step", str(step)]
    data = yaml.safe_load(path.read_text())
    data["workspace"]["grid"]["step"] = [float(s) for s in step]
    copy = b.folder(f"{name}-spec") / path.name
    copy.write_text(yaml.safe_dump(data, sort_keys=False))
    return str(copy), []


def grid_of(design, step):
    from cdpr_design import workspaces as ws
    from cdpr_design.model.design import Grid

    if step is None or np.isscalar(step):
        return ws.make_grid(design, step, force=True)
    g = design.workspace.grid
    return Grid(g.lower, g.upper, tuple(float(s) for s in step))


#: The kernels of a checkout in a child process: ``workspaces.run`` without maps or rows on the
#: grid of the spec ``argv[1]`` (``argv[2]`` a ``--step``, or empty: the spec's own grid), once
#: untimed (numba's cache loaded), then timed; prints {"cpu": CPU-s, "wall": s} as JSON.
KERNEL_CHILD = """
import json, sys, time
from cdpr_design import workspaces as ws
from cdpr_design.model import spec
d = spec.load(sys.argv[1])
g = ws.make_grid(d, float(sys.argv[2]) if sys.argv[2] else None, force=True)
ws.run(d, grid=g, keep_maps=False)
t0, c0 = time.perf_counter(), time.process_time()
ws.run(d, grid=g, keep_maps=False)
print(json.dumps({"cpu": time.process_time() - c0, "wall": time.perf_counter() - t0}))
"""


def kernels_in_child(root, spec: str, extra: list[str]) -> h.Timing:
    """:data:`KERNEL_CHILD` on the checkout ``root``: the kernels' warm sweep, in a new process."""
    got = h.child_json(KERNEL_CHILD, spec, extra[1] if extra else "", root=root)
    return h.Timing(got["wall"], got["cpu"])


def workspace_command(b: h.Bench, root, spec: str, extra: list[str], fmt: str, cache=None):
    args = ["workspace", spec, *extra, "--out", str(b.folder("out")), "--overwrite", "--format", fmt]
    return h.command(args, root=root, cache=cache)


def bench_design(b: h.Bench, name: str, step) -> None:
    """Rounds of (LP, kernels warm, whole commands, LP again) for one design, as rows."""
    from cdpr_design import workspaces as ws
    from cdpr_design.model import spec

    d = spec.load(h.ROOT / "designs" / f"{name}.yaml")
    g = grid_of(d, step)
    poses = lp_poses(d, g, b.opt["sample"], b.rng)
    label = f"{name}, {g.size:,} poses (step {step if step is not None else d.workspace.grid.step[0]} m)"
    b.say(f"{label}: per-pose linprog over {len(poses)} poses, {b.rounds} rounds")
    roots = {"this": h.ROOT} | ({"baseline": b.baseline} if b.baseline else {})
    specs = {k: spec_file(b, r, name, step) for k, r in roots.items()}
    first, _ = h.timed(ws.run, d, grid=g, keep_maps=False)
    scale = g.size / len(poses)

    def lp():
        t, _ = h.timed(linprog_feasible, d, poses)
        return t

    if b.opt["cold"]:
        lp0 = lp()
        t, s = workspace_command(b, h.ROOT, *specs["this"], "csv", cache=b.fresh_cache())
        b.row(f"{label}: whole command, cold numba cache (csv)", f"{t.wall:.2f} s, {t.cpu:.1f} CPU-s, load_s "
              f"{s.get('timings', {}).get('load_s', float('nan')):.2f} s", h.ratios([lp0], [t], scale=scale),
              "per-pose linprog")
    for k, (path, extra) in specs.items():
        for fmt in b.opt["formats"]:
            workspace_command(b, roots[k], path, extra, fmt)  # numba's cache and the bytecode warm
    b.row(f"{label}: kernels in-process, first call", f"{first.wall:.3f} s")
    lp_wall, lp_cpu, kern, cmds, sweeps, child = [], [], [], {}, {}, {}
    for _ in range(b.rounds):
        before = lp()
        kt, _ = h.timed(ws.run, d, grid=g, keep_maps=False)
        if "baseline" in roots:  # each checkout's kernels in a child, one after the other
            for k in roots:
                child.setdefault(k, []).append(kernels_in_child(roots[k], *specs[k]))
        runs = {(k, fmt): workspace_command(b, roots[k], *specs[k], fmt)
                for k in roots for fmt in b.opt["formats"]}
        after = lp()
        lp_wall.append((before.wall + after.wall) / 2)
        lp_cpu.append((before.cpu + after.cpu) / 2)
        kern.append(kt)
        for key, (t, s) in runs.items():
            cmds.setdefault(key, []).append(t)
            timings = s.get("timings", {})
            sweeps.setdefault(key, []).append(timings.get("sweep_s", s.get("elapsed_s")))
    b.say(f"per-pose linprog {h.spread(x / len(poses) * 1e3 for x in lp_wall).text()} ms over the rounds")
    b.row(f"{label}: kernels in-process, warm", h.seconds(h.spread(t.wall for t in kern)),
          h.ratios(lp_wall, kern, scale=scale), "per-pose linprog (wall)")
    b.row(f"{label}: kernels in-process, warm, CPU", h.seconds(h.spread(t.cpu for t in kern)),
          h.ratios(lp_cpu, kern, "cpu", scale=scale), "per-pose linprog (CPU)")
    if child:
        for what in ("wall", "cpu"):
            b.row(f"{label}: kernels in a child process, warm, {what}, this checkout",
                  h.seconds(h.spread(t.get(what) for t in child["this"])), h.ratios(child["baseline"], child["this"], what),
                  "the baseline checkout's kernels (the same rounds)")
    for (k, fmt), times in cmds.items():
        who = "" if k == "this" else " [baseline checkout]"
        b.row(f"{label}: whole command, warm ({fmt}){who}", h.seconds(h.spread(t.wall for t in times)),
              h.ratios(lp_wall, times, scale=scale), "per-pose linprog (wall)")
        b.row(f"{label}: whole command, warm ({fmt}){who}, CPU", f"{h.spread(t.cpu for t in times).text()} CPU-s",
              h.ratios(lp_cpu, times, "cpu", scale=scale), "per-pose linprog (CPU)")
        b.row(f"{label}: its sweep_s ({fmt}){who}", h.seconds(h.spread(sweeps[k, fmt])),
              h.ratios(lp_wall, sweeps[k, fmt], scale=scale), "per-pose linprog (wall)")
        if k == "this" and "baseline" in roots:
            b.row(f"{label}: whole command ({fmt}), this checkout", h.seconds(h.spread(t.wall for t in times)),
                  h.ratios(cmds["baseline", fmt], times), "the baseline checkout's command")


def previous_format_block(columns, int_cols) -> str:
    """The first CSV writer of workspace rows: one printf per row, NaN cells removed by a regex."""
    ints = set(int_cols)
    fmt = ",".join("%d" if j in ints else "%.10g" for j in range(len(columns)))
    block = np.column_stack([np.asarray(c, dtype=float) for c in columns])
    text = "\n".join([fmt % row for row in map(tuple, block.tolist())]) + "\n"
    return re.sub(r"(?<![^,\n])-?(?:nan|inf)(?![^,\n])", "", text)


def writer(b: h.Bench, step) -> None:
    """The CSV formatters alone on the design's rows: the first writer and the writer's
    cell-by-cell path against the compiled one (warm; and its first call in this process, numba's cache warm)."""
    from cdpr_design import workspaces as ws
    from cdpr_design.io import csvfast
    from cdpr_design.io.tables import cell_rows
    from cdpr_design.model import spec

    h.python("import numpy; from cdpr_design.io.csvfast import numba_rows; numba_rows([numpy.ones(3)])")
    d = spec.load(h.ROOT / "designs" / f"{b.opt['design']}.yaml")
    chunks = []
    ws.run(d, grid=grid_of(d, step), keep_maps=False, on_chunk=chunks.append)

    def cols(c):
        return ([c.poses[:, j] for j in range(c.poses.shape[1])] + [c.feasible, c.margin]
                + [c.tensions[:, i] for i in range(c.tensions.shape[1])]
                + [c.lengths[:, i] for i in range(c.lengths.shape[1])])

    k = chunks[0].poses.shape[1]
    cells = sum(len(cols(c)) * len(c.feasible) for c in chunks)
    first, _ = h.timed(lambda: [csvfast.numba_rows(cols(c)) for c in chunks])
    t = h.rounds({"previous": lambda: [previous_format_block(cols(c), [k]) for c in chunks],
                  "cells": lambda: [cell_rows(cols(c)) for c in chunks],
                  "numba": lambda: [csvfast.numba_rows(cols(c)) for c in chunks]}, b.rounds)

    def ns(times):
        return f"{h.spread(x.wall / cells * 1e9 for x in times).text('.0f')} ns a cell"

    b.row(f"CSV of {b.opt['design']}'s rows ({cells:,} cells): numba formatter", ns(t["numba"]),
          h.ratios(t["cells"], t["numba"]), "Python's format a column at a time", f"first call {first.wall / cells * 1e9:.0f} ns a cell")
    b.row(f"CSV of {b.opt['design']}'s rows: numba formatter", ns(t["numba"]), h.ratios(t["previous"], t["numba"]),
          "printf per row")


def run(b: h.Bench) -> None:
    from cdpr_design.kernels import parallel

    b.say(f"kernel threads {parallel.threads()}")
    if b.opt["floor"]:
        for what, code in FLOOR.items():
            h.python(code)  # bytecode and numba's cache written
            times = [h.python(code)[0] for _ in range(b.rounds)]
            b.row(f"fixed cost: {what}", f"{h.best(times):.3f} s (best of {len(times)}, wall)")
    bench_design(b, b.opt["design"], b.opt["step"])
    if b.opt["planar2"]:
        bench_design(b, "planar2", None)
        if b.opt["planar2_step"]:
            bench_design(b, "planar2", b.opt["planar2_step"])
    if b.opt["writer_step"]:
        writer(b, b.opt["writer_step"])
