"""What ``workspace --accelerations`` costs against the plain sweep, and the acceleration kernel alone.

For each design: the whole workspace sweep as a command runs it (``workspaces.run``: the plan, its
wrappers, the maps; no files), with and without ``accelerations=True``, the two runs of a round
back to back (each order in every other round), CPU on ``threads`` kernel threads: the median and
range of the rounds' own ratios.  Then the acceleration kernel alone
(:func:`cdpr_design.statics.acceleration.at_positions` on the design's grid positions in chunks:
the batched structure matrices and ``kernels.acceleration.capability_many``), CPU a pose.
"""

from __future__ import annotations

import time

from benchmarks import harness as h

OPTIONS = {"designs": ("planar2", "ipanema3"), "threads": 2}
QUICK = {"designs": ("planar2",)}

CHUNK = 65536


def kernel_pass(design) -> float:
    """CPU-s of the acceleration capability at every grid position of ``design``."""
    from cdpr_design.statics import acceleration as acc
    from cdpr_design.statics.robot import Analysis, resolve
    from cdpr_design.workspaces.grid import positions3

    robot = resolve(design, Analysis(accelerations=True))
    ld = acc.loads(robot, design.default_orientation_full())
    g = design.workspace.grid
    total = 0.0
    for start in range(0, g.size, CHUNK):
        P = positions3(g, start, min(CHUNK, g.size - start))
        c0 = time.process_time()
        acc.at_positions(robot, ld, P)
        total += time.process_time() - c0
    return total


def run(b: h.Bench) -> None:
    from cdpr_design.kernels import parallel
    from cdpr_design.model import spec

    designs = {n: spec.load(h.ROOT / "designs" / f"{n}.yaml") for n in b.opt["designs"]}
    with parallel.threads_kept():
        parallel.set_threads(b.opt["threads"])
        h.option_cost(b, designs, "accelerations", "--accelerations", b.opt["threads"])
        for n, d in designs.items():
            cpu = min(kernel_pass(d) for _ in range(b.rounds))
            b.row(f"{n}: the acceleration capability alone (structure matrices and kernel, CPU)",
                  h.per_pose(cpu, d.workspace.grid.size))
