"""What the workspace's boundary and the frame loads add to a sweep (``workspaces.run(solid=True)``).

For each design, on the grid of ``steps`` [m] per axis (IPAnema 3's default: (0.1, 0.1, 0.05),
838,201 poses), warm (the kernels compiled or loaded outside the timing), in interleaved
rounds in this process: the plain sweep (the baseline), the sweep with the frame loads alone,
and the sweep with the boundary between the grid points and the frame loads, CPU of this process
(threads included); the ratio of each round to the plain sweep of the same round, the machine's
load average over the rounds, the boundary's own wall time (contouring, refinement with the exact
test, welding) and its vertices and triangles.
"""

from __future__ import annotations

import os

from benchmarks import harness as h

OPTIONS = {"designs": ("ipanema3",), "steps": (0.1, 0.1, 0.05)}
QUICK = {"steps": (0.2, 0.2, 0.1)}


def run(b: h.Bench) -> None:
    from cdpr_design import workspaces as ws
    from cdpr_design.model import spec
    from cdpr_design.model.design import Grid
    from cdpr_design.statics.robot import resolve

    for name in b.opt["designs"]:
        d = spec.load(h.ROOT / "designs" / f"{name}.yaml")
        g0 = d.workspace.grid
        g = Grid(g0.lower, g0.upper, tuple(float(s) for s in b.opt["steps"])[:len(g0.lower)])
        robot = resolve(d)
        ws.plan(robot, Grid(g.lower, g.upper, tuple(4 * s for s in g.step)), solid=True).run()  # kernels, imports
        results, loads = {}, []

        def sweep(**parts):
            t, r = h.timed(ws.plan(robot, g, **parts).run)
            results[tuple(parts.items())] = r
            loads.append(os.getloadavg()[0])
            return t

        got = h.rounds({"plain": lambda: sweep(), "frame loads": lambda: sweep(frame_loads=True),
                        "solid": lambda: sweep(solid=True)}, b.rounds)
        bnd = results[(("solid", True),)].boundary
        load = f"load average {h.spread(loads).text('.1f')}"
        b.row(f"{name}, {g.size:,} poses: the plain sweep", h.seconds(h.spread(t.cpu for t in got["plain"])) + " CPU",
              note=load)
        b.row(f"{name}, {g.size:,} poses: the sweep with the frame loads",
              h.seconds(h.spread(t.cpu for t in got["frame loads"])) + " CPU",
              h.ratios(got["frame loads"], got["plain"], "cpu"), "the plain sweep (CPU)", load)
        b.row(f"{name}, {g.size:,} poses: the sweep with the boundary and the frame loads",
              h.seconds(h.spread(t.cpu for t in got["solid"])) + " CPU",
              h.ratios(got["solid"], got["plain"], "cpu"), "the plain sweep (CPU)",
              f"{load}; boundary {bnd.elapsed_s:.3g} s wall, {len(bnd.vertices) or sum(map(len, bnd.loops)):,} "
              f"vertices, {len(bnd.faces):,} triangles")
