"""Benchmark of ``certify`` against a grid sweep in the same process.

For each resolution h: the certified paving of the design's grid box (CPU seconds, inner,
boundary and outer measure) and the grid sweep at step h (``workspaces.run``: CPU seconds and the
feasible volume, feasible fraction x box measure).  Reports the inner measure as a fraction of the
grid's feasible measure, the boundary as a fraction of the box, and the time ratio certify / grid,
so the growth of time with 1/h can be read off.  CPU time (``time.process_time``): the machine
is shared.

    python scripts/bench_certify.py designs/planar2.yaml 0.01 0.005 0.002 0.001
    python scripts/bench_certify.py designs/ipanema3.yaml 0.4 0.2 0.1 --max-boxes 400000
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import cdpr_design as cd
from cdpr_design import workspaces as ws
from cdpr_design.model.design import Grid
from cdpr_design.workspaces.certify import certify, warm_up


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("spec")
    ap.add_argument("resolutions", type=float, nargs="+")
    ap.add_argument("--max-boxes", type=int, default=2_000_000)
    a = ap.parse_args()
    d = cd.load(a.spec)
    warm_up(d)
    g0 = d.workspace.grid
    ws.run(d, grid=Grid(g0.lower, g0.lower, g0.step), force=True, engine="numba", keep_maps=False, tilt=False)
    print(f"{'h [m]':>8} {'certify CPU-s':>13} {'boxes':>9} {'inner':>9} {'outer':>9} {'bnd/box %':>9} "
          f"{'grid CPU-s':>10} {'grid feas':>9} {'inner/grid':>10} {'time ratio':>10} {'stop':>9}")
    for h in a.resolutions:
        t = time.process_time()
        r = certify(d, resolution=h, max_boxes=a.max_boxes)
        tc = time.process_time() - t
        s = r.summary()
        t = time.process_time()
        g = Grid(g0.lower, g0.upper, (h,) * len(g0.lower))
        w = ws.run(d, grid=g, force=True, engine="numba", keep_maps=False, tilt=False)
        tg = time.process_time() - t
        feas = w.feasible / w.poses * s["box_measure"]
        print(f"{h:8.4g} {tc:13.3f} {s['boxes_classified']:9d} {s['inner_measure']:9.5g} {s['outer_measure']:9.5g} "
              f"{100 * s['boundary_measure'] / s['box_measure']:9.3g} {tg:10.3f} {feas:9.5g} "
              f"{s['inner_measure'] / feas:10.4f} {tc / max(tg, 1e-9):10.3g} {s['truncated'] or '-':>9}", flush=True)


if __name__ == "__main__":
    np.set_printoptions(precision=4)
    main()
