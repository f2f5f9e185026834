"""What the workspace's boundary and frame loads add to a sweep: IPAnema 3 on its 1.15 M-pose grid.

Sweeps designs/ipanema3.yaml on the grid of steps (0.1, 0.1, 0.05) m, in interleaved pairs in
one process: the plain sweep (the baseline) and the sweep planned with ``solid`` (the boundary
between the grid points and the frame loads). Prints per pair the CPU-s (this process, threads
included) and wall seconds of each, their ratio, and the boundary's own wall time
(contouring, refinement, welding) with its vertex and triangle counts.

Run from the repository root: python scripts/bench_boundary.py [--pairs N]
"""

from __future__ import annotations

import argparse
import time

from cdpr_design import workspaces as ws
from cdpr_design.model import spec
from cdpr_design.model.design import Grid


def timed(p):
    c0, w0 = time.process_time(), time.perf_counter()
    r = p.run()
    return r, time.process_time() - c0, time.perf_counter() - w0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--pairs", type=int, default=3)
    args = ap.parse_args()
    d = spec.load("designs/ipanema3.yaml")
    g0 = d.workspace.grid
    g = Grid(g0.lower, g0.upper, (0.1, 0.1, 0.05))
    robot = ws.robot_for(d, g)
    print(f"IPAnema 3, grid {g.shape}: {g.size:,} poses")
    ws.warm_up(ws.plan(robot, g, solid=True))
    timed(ws.plan(robot, Grid(g.lower, g.upper, (0.2, 0.2, 0.2)), solid=True))  # imports, kernels
    for k in range(args.pairs):
        _, c_plain, w_plain = timed(ws.plan(robot, g))
        r, c_solid, w_solid = timed(ws.plan(robot, g, solid=True))
        b = r.boundary
        print(f"pair {k + 1}: plain {c_plain:.2f} CPU-s / {w_plain:.2f} s, with boundary and frame loads "
              f"{c_solid:.2f} CPU-s / {w_solid:.2f} s (x{c_solid / c_plain:.2f} CPU, x{w_solid / w_plain:.2f} wall); "
              f"boundary {b.elapsed_s:.2f} s, {len(b.vertices):,} vertices, {len(b.faces):,} triangles; "
              f"boundary_measure {b.measure:.4f} m^3, measure {r.measure:.4f} m^3")


if __name__ == "__main__":
    main()
