"""The workspace's boundary against exact areas and volumes, step by step.

Prints, for the seed paper's robot (designs/planar2.yaml), a point mass on two cables with a
lower tension bound and the sensor pod of designs/pointmass3.yaml with a 60 N tension limit,
at several grid steps: the exact area or volume (tests/reference_boundary.py, closed form and
quadrature), the grid count ``measure`` and ``boundary_measure`` with their relative errors,
and the boundary's time against the sweep's (CPU-s of this process, threads included).

Run from the repository root: python scripts/boundary_accuracy.py
"""

from __future__ import annotations

import time

from cdpr_design import workspaces as ws
from cdpr_design.model import spec
from cdpr_design.statics.robot import resolve
from tests.reference_boundary import planar_area, spatial_volume
from tests.test_boundary import box_top, planar2_exact, pod_data, twocable_data


def run(design, step):
    g = ws.make_grid(design, step)
    p = ws.plan(resolve(design), g, solid=True)
    c0 = time.process_time()
    r = p.run()
    return r, time.process_time() - c0


def main() -> None:
    cases = [
        ("planar2", spec.load("designs/planar2.yaml"), (0.1, 0.05, 0.025, 0.01),
         lambda d, g: planar2_exact(d, g)),
        ("two-cable point mass", spec.from_dict(twocable_data()), (0.1, 0.05, 0.025, 0.01),
         lambda d, g: planar_area(0.25, 3.25, 3.3, 2.0 * 9.81, 5.0, 60.0, g.lower[1], box_top(g, 1))),
        ("pod, 60 N", spec.from_dict(pod_data()), (1.0, 0.5, 0.25, 0.125),
         lambda d, g: spatial_volume(d.outlets[:, :2], 6.0, 5.0 * 9.81, 60.0, g.lower[2], box_top(g, 2),
                                     box_top(g, 1))),
    ]
    print("| robot | step [m] | poses | exact | grid count (error) | boundary_measure (error) | boundary / sweep CPU |")
    print("|---|---|---|---|---|---|---|")
    for name, d, steps, exact in cases:
        run(d, steps[0])  # imports and kernels loaded
        for step in steps:
            r, cpu = run(d, step)
            x = exact(d, r.grid)
            b = r.boundary
            print(f"| {name} | {step:g} | {r.poses:,} | {x:.5f} | {r.measure:.5f} ({(r.measure / x - 1) * 100:+.3f} %) "
                  f"| {b.measure:.5f} ({(b.measure / x - 1) * 100:+.4f} %) | {b.elapsed_s:.3f} / {cpu:.3f} s |")


if __name__ == "__main__":
    main()
