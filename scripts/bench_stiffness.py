"""Benchmark: the stiffness kernel's cost relative to the sweep kernel on the same grid (issue 39, item 5).

For each design, in this one process and on one thread: the grid sweep's kernel
(``kernels.sweep_grid``: feasibility, capacity margin, minimum-norm tensions) over the design's
workspace grid in chunks, then the stiffness kernel
(:func:`cdpr_design.statics.stiffness.sweep_figures`: least stiffness and lowest natural
frequency) on the same rows with the sweep's tensions.  CPU time (``time.process_time``), the
best of ``--repeat`` interleaved rounds; the kernels are compiled (or loaded) before timing.
Prints both per-pose costs and the ratio (sweep + stiffness) / sweep; the issue's target is
<= 2.  Then the whole workspace sweep as a command runs it (``workspaces.run``: the sweep plan,
its wrappers, the maps; no files), without and with ``stiffness=True``, CPU time on the
kernels' threads (``--threads``), the best of ``--repeat`` interleaved rounds, and the ratio.

    python scripts/bench_stiffness.py                 # cogiro, planar4, pointmass3, planar2, sagging40 (elastic)
    python scripts/bench_stiffness.py --repeat 5 cogiro
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cdpr_design import kernels as K  # noqa: E402
from cdpr_design import workspaces as ws  # noqa: E402
from cdpr_design.kernels import parallel  # noqa: E402
from cdpr_design.model import spec  # noqa: E402
from cdpr_design.statics import kinematics as kin  # noqa: E402
from cdpr_design.statics import stiffness as st  # noqa: E402
from cdpr_design.statics.pose import KINDS, combinations, wrench_vertices  # noqa: E402
from cdpr_design.workspaces.grid import grid3, positions3  # noqa: E402

CHUNK = 65536


def design_of(name: str):
    d = spec.load(ROOT / "designs" / f"{name}.yaml")
    if st.axial_stiffnesses(d)[1] is not None:  # sagging: its straight elastic twin
        d = spec.from_dict({**d.raw, "cable": {**d.raw.get("cable", {}), "model": "elastic"}})
    return d


def run(design):
    """(sweep CPU-s, stiffness CPU-s, poses, feasible) for one pass over the grid."""
    g = design.workspace.grid
    ori = design.default_orientation_full()
    R = kin.rotation_matrix(*ori)
    Rb, A = np.ascontiguousarray(design.attachments @ R.T), np.ascontiguousarray(design.outlets)
    wreq = wrench_vertices(design, "static", ori)
    combos = combinations(design.m, design.n)
    lower, step, shape = grid3(g)
    arrays = st.sweep_arrays(design, ori)
    t_sweep = t_stiff = 0.0
    feasible = 0
    for start in range(0, g.size, CHUNK):
        cnt = min(CHUNK, g.size - start)
        feas = np.empty(cnt, np.uint8)
        marg = np.empty(cnt)
        ten = np.empty((cnt, design.m))
        lens = np.empty((cnt, design.m))
        c0 = time.process_time()
        K.sweep_grid(start, cnt, lower, step, shape, Rb, A, design.rows, wreq, design.tension_min,
                     design.tension_max, design.string_floor, combos, KINDS["static"], feas, marg, ten, lens)
        c1 = time.process_time()
        P = positions3(g, start, cnt)
        c2 = time.process_time()
        kmin, flow = st.sweep_figures(arrays, P, ten)
        c3 = time.process_time()
        t_sweep += c1 - c0
        t_stiff += c3 - c2
        feasible += int(feas.sum())
    return t_sweep, t_stiff, g.size, feasible


def whole_sweep(design, stiffness: bool) -> float:
    """CPU seconds of ``workspaces.run`` over the design's grid (maps kept, no rows written)."""
    c0 = time.process_time()
    ws.run(design, stiffness=stiffness, tilt=False)
    return time.process_time() - c0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("designs", nargs="*", default=["cogiro", "planar4", "pointmass3", "planar2", "sagging40"])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1, help="kernel threads of the whole-sweep rounds")
    args = ap.parse_args()
    parallel.set_threads(1)
    designs = {n: design_of(n) for n in args.designs}
    for d in designs.values():  # compile / load both kernels outside the timing
        run(d.replace(workspace=d.workspace.__class__(
            grid=d.workspace.grid.__class__(d.workspace.grid.lower, d.workspace.grid.lower,
                                            d.workspace.grid.step), orientation=d.workspace.orientation)))
    best = {n: (np.inf, np.inf, 0, 0) for n in designs}
    for _ in range(args.repeat):
        for n, d in designs.items():
            ts, tk, poses, feas = run(d)
            b = best[n]
            best[n] = (min(b[0], ts), min(b[1], tk), poses, feas)
    print(f"{'design':12s} {'motion':6s} {'m':>2s} {'poses':>8s} {'feasible':>8s} {'sweep us':>9s} "
          f"{'stiff us':>9s} {'ratio':>6s}")
    for n, (ts, tk, poses, feas) in best.items():
        d = designs[n]
        print(f"{n:12s} {d.motion.name:6s} {d.m:2d} {poses:8d} {feas:8d} {1e6 * ts / poses:9.3f} "
              f"{1e6 * tk / poses:9.3f} {(ts + tk) / ts:6.2f}")
    parallel.set_threads(args.threads)
    for d in designs.values():  # the plan's other kernels loaded outside the timing
        one = ws.make_grid(d)
        ws.run(d, grid=ws.grid.first_pose(one), stiffness=True, tilt=False)
        ws.run(d, grid=ws.grid.first_pose(one), tilt=False)
    whole = {n: [np.inf, np.inf] for n in designs}
    for _ in range(args.repeat):
        for n, d in designs.items():
            whole[n][0] = min(whole[n][0], whole_sweep(d, False))
            whole[n][1] = min(whole[n][1], whole_sweep(d, True))
    print(f"\nthe whole workspace sweep ({args.threads} thread(s)), CPU-s")
    print(f"{'design':12s} {'without':>9s} {'with':>9s} {'ratio':>6s}")
    for n, (a, b) in whole.items():
        print(f"{n:12s} {a:9.3f} {b:9.3f} {b / a:6.2f}")


if __name__ == "__main__":
    main()
