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
that design's arrays left): the median and range of the rounds' own ratios.  A sagging design is
measured as its straight elastic twin.
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks import harness as h

OPTIONS = {"designs": ("cogiro", "planar4", "pointmass3", "planar2", "sagging40"), "threads": 1}
QUICK = {"designs": ("cogiro", "planar2")}

CHUNK = 65536


def design_of(name: str):
    from cdpr_design.model import spec
    from cdpr_design.statics import stiffness as st

    d = spec.load(h.ROOT / "designs" / f"{name}.yaml")
    if st.axial_stiffnesses(d)[1] is not None:  # sagging: its straight elastic twin
        d = spec.from_dict({**d.raw, "cable": {**d.raw.get("cable", {}), "model": "elastic"}})
    return d


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

    base = StraightSweep(resolve(design), ori, g)  # the closed form for two cables, else the kernels
    t_sweep = t_stiff = 0.0
    feasible = 0
    for start in range(0, g.size, CHUNK):
        cnt = min(CHUNK, g.size - start)
        c0 = time.process_time()
        rows = base.rows(start, cnt, None)
        feas, ten = rows.feasible, rows.tensions
        c1 = time.process_time()
        kmin, flow = st.grid_figures(arrays, (lower, step, shape), start, ten, feas)
        c2 = time.process_time()
        t_sweep += c1 - c0
        t_stiff += c2 - c1
        feasible += int(feas.sum())
    return t_sweep, t_stiff, g.size, feasible


def run(b: h.Bench) -> None:
    from cdpr_design import workspaces as ws
    from cdpr_design.kernels import parallel

    designs = {n: design_of(n) for n in b.opt["designs"]}
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
        for d in designs.values():  # the plan's other kernels loaded outside the timing
            one = ws.grid.first_pose(ws.make_grid(d))
            ws.run(d, ws.Analysis(stiffness=True), grid=one, tilt=False)
            ws.run(d, grid=one, tilt=False)
        for n, d in designs.items():
            pairs = []
            for r in range(b.rounds):
                pair = {}
                for stiffness in ((False, True) if r % 2 == 0 else (True, False)):
                    pair[stiffness], _ = h.timed(ws.run, d, ws.Analysis(stiffness=stiffness), tilt=False)
                pairs.append(pair)
            b.row(f"{n}: the whole workspace sweep with stiffness", h.seconds(h.spread(p[True].cpu for p in pairs))
                  + " CPU", h.ratios([p[True] for p in pairs], [p[False] for p in pairs], "cpu"),
                  f"time ÷ without stiffness (CPU, {b.opt['threads']} thread(s))")
