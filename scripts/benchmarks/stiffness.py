"""The stiffness kernel's cost beside the sweep kernel's on the same grid.

For each design, in this process on one thread: the grid sweep's kernel as the workspace sweep
calls it (``workspaces.engine.StraightSweep``: the kernels, or numpy's closed form for two cables and two wrench
rows) over the design's grid in chunks, then the stiffness kernel
(:func:`cdpr_design.statics.stiffness.grid_figures`: least stiffness and lowest natural frequency)
on the same rows with the sweep's tensions and feasibility, CPU time, interleaved rounds, the
kernels compiled (or loaded) before timing: (sweep + stiffness) / sweep.  Then the whole workspace
sweep as a command runs it (``workspaces.run``: the plan, its wrappers, the maps; no files), with
and without ``stiffness=True``, CPU on ``threads`` kernel threads, the two runs of a round back to
back (each order in every other round: the first run after another design's pays for the memory
that design's arrays left): the median and range of the rounds' own ratios.  ``sagging40`` is
measured with its sagging cables (the catenary sweep, and the catenaries' stiffness from the
unstretched lengths) and, as ``sagging40:elastic``, as its straight elastic twin, both on the grid
of ``sagging_step`` [m].
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks import harness as h

OPTIONS = {"designs": ("cogiro", "planar4", "pointmass3", "planar2", "sagging40", "sagging40:elastic"), "threads": 1,
           "sagging_step": 0.5}
QUICK = {"designs": ("cogiro", "planar2", "sagging40", "sagging40:elastic")}

CHUNK = 65536


def design_of(name: str, sagging_step: float):
    """The shipped design ``name`` (``NAME:elastic``: its straight elastic twin); sagging40 and its
    twin on the grid of ``sagging_step`` [m]."""
    from cdpr_design.model import spec

    base, _, model = name.partition(":")
    d = spec.load(h.ROOT / "designs" / f"{base}.yaml")
    raw = dict(d.raw)
    if model:
        raw["cable"] = {**raw.get("cable", {}), "model": model}
    if base == "sagging40":
        ws = raw["workspace"]
        raw["workspace"] = {**ws, "grid": {**ws["grid"], "step": sagging_step}}
    return spec.from_dict(raw) if raw != d.raw else d


def passes(design):
    """(sweep CPU-s, stiffness CPU-s, poses, feasible) for one pass over the grid."""
    from cdpr_design import kernels as K
    from cdpr_design.statics import kinematics as kin
    from cdpr_design.statics import stiffness as st
    from cdpr_design.statics.robot import KINDS, combinations
    from cdpr_design.statics.wrenches import wrench_vertices
    from cdpr_design.workspaces.grid import grid3

    g = design.workspace.grid
    ori = design.default_orientation_full()
    R = kin.rotation_matrix(*ori)
    Rb, A = np.ascontiguousarray(design.attachments @ R.T), np.ascontiguousarray(design.outlets)
    wreq = wrench_vertices(design, "static", ori)
    combos = combinations(design.m, design.n)
    lower, step, shape = grid3(g)
    arrays = st.sweep_arrays(design, ori)
    from cdpr_design.statics.robot import resolve
    from cdpr_design.workspaces.engine import StraightSweep

    robot = resolve(design)
    if robot.cables.straight:
        base = StraightSweep(robot, ori, g)  # the closed form for two cables, else the kernels
        names = None
    else:
        from cdpr_design.workspaces.cables import SaggingSweep

        base = SaggingSweep(robot, ori, g)
        names = [f"unstretched_length_{c}" for c in design.cable_names]
    t_sweep = t_stiff = 0.0
    feasible = 0
    for start in range(0, g.size, CHUNK):
        cnt = min(CHUNK, g.size - start)
        c0 = time.process_time()
        rows = base.rows(start, cnt, None)
        feas, ten = rows.feasible, rows.tensions
        L0 = None if names is None else np.column_stack([rows.extra[c] for c in names])
        c1 = time.process_time()
        kmin, flow = st.grid_figures(arrays, (lower, step, shape), start, ten, feas, L0)
        c2 = time.process_time()
        t_sweep += c1 - c0
        t_stiff += c2 - c1
        feasible += int(feas.sum())
    return t_sweep, t_stiff, g.size, feasible


def run(b: h.Bench) -> None:
    from cdpr_design.kernels import parallel

    designs = {n: design_of(n, float(b.opt["sagging_step"])) for n in b.opt["designs"]}
    with parallel.threads_kept():
        parallel.set_threads(1)
        for d in designs.values():  # both kernels compiled or loaded outside the timing
            g = d.workspace.grid
            passes(d.replace(workspace=d.workspace.__class__(grid=g.__class__(g.lower, g.lower, g.step),
                                                             orientation=d.workspace.orientation)))
        got = {n: [] for n in designs}
        for _ in range(b.rounds):
            for n, d in designs.items():
                got[n].append(passes(d))
        for n, runs in got.items():
            poses, feas = runs[0][2], runs[0][3]
            d = designs[n]
            b.row(f"{n} ({d.motion.name}, m = {d.m}, {poses:,} poses, {feas:,} feasible): stiffness kernel",
                  f"{h.per_pose(min(r[1] for r in runs), poses)} (sweep {h.per_pose(min(r[0] for r in runs), poses)})",
                  h.spread((r[0] + r[1]) / r[0] for r in runs), "(sweep + stiffness) ÷ sweep, CPU, one thread")
        parallel.set_threads(b.opt["threads"])
        h.option_cost(b, designs, "stiffness", "stiffness", b.opt["threads"])
