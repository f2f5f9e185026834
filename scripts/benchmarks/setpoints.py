"""Real-cable set-points along a path against a per-pose loop; the massive-cable simulation.

Sampling (``trajectory``): the slow square on planar2 (8,121 samples at 1 ms) with ideal, elastic
and sagging cables, and, as the baseline in the same rounds, the sagging statics of the same
samples one pose at a time through the per-pose kernel (``tests/reference_pose.py``'s
``sagging_pose``) in a Python loop: samples/s, the sagging cost against the ideal sampling and the
batched kernel's speed-up over the per-pose loop; the first call of each model in this process
(compile or cache load) is reported too.

Simulation (``simulate``): the fast square with ideal, elastic and sagging cables (16 segments
each), wall and CPU time and the CPU ratio to the ideal run.
"""

from __future__ import annotations

import sys

import numpy as np

from benchmarks import harness as h

OPTIONS = {"simulate": True}
QUICK = {"simulate": False}


def per_pose_loop(design, samples):
    """The sagging statics of every sample through the per-pose function (the baseline)."""
    sys.path.insert(0, str(h.ROOT))
    from cdpr_design.motion import trajectory
    from cdpr_design.statics.robot import Analysis, combinations, resolve
    from tests.reference_pose import sagging_pose

    st = trajectory.states(resolve(design, Analysis(command="motion")), samples.pose, samples.velocity, samples.acceleration)
    combos = combinations(design.m, design.n)
    out = np.empty((len(samples), design.m))
    for j in range(len(samples)):
        _, _, _, _, _, state = sagging_pose(design, design.full_pose(samples.pose[j]),
                                            st["wrench"][j:j + 1].copy(), combos, 0)
        out[j] = state.unstretched_lengths
    return out


def run(b: h.Bench) -> None:
    from cdpr_design.model import spec
    from cdpr_design.motion import run as motion_run
    from cdpr_design.motion import trajectory
    from cdpr_design.statics.robot import Analysis, resolve

    base = spec.load(h.ROOT / "designs" / "planar2.yaml")
    designs = {m: base if m == "ideal" else spec.with_cable_model(base, m) for m in ("ideal", "elastic", "sagging")}
    first = {m: h.timed(trajectory.sample, d, "square_slow") for m, d in designs.items()}
    d = designs["sagging"]
    s = first["sagging"][1]
    ref = per_pose_loop(d, s)
    assert np.allclose(ref, s.cables.unstretched, rtol=1e-12, equal_nan=True)
    variants = {m: (lambda d=d: trajectory.sample(resolve(d, Analysis(command="motion")), "square_slow")) for m, d in designs.items()}
    t = h.rounds(variants | {"loop": lambda: per_pose_loop(d, s)}, b.rounds)
    n = len(s)
    for m in designs:
        b.row(f"planar2 square_slow set-points, {m} cables ({n:,} samples)",
              f"{n / h.best(t[m]):,.0f} samples/s, first call {first[m][0].wall:.2f} s",
              h.ratios(t[m], t["ideal"]) if m != "ideal" else None,
              "time ÷ the ideal sampling's" if m != "ideal" else "")
    b.row(f"planar2 square_slow set-points, sagging cables, batched", f"{n / h.best(t['sagging']):,.0f} samples/s",
          h.ratios(t["loop"], t["sagging"]), "a per-pose loop of the sagging statics")
    if not b.opt["simulate"]:
        return
    times = {}
    for m, dm in designs.items():
        robot = resolve(dm, Analysis(command="motion"))
        samples = trajectory.sample(robot, "square_fast", hold_end=0.5)
        times[m], res = h.timed(motion_run.simulate, robot, samples)
        sub = f", {res.settings['cable_segments']} segments a cable" if "cable_segments" in res.settings else ""
        b.row(f"planar2 simulate square_fast, {m} cables{sub}", f"{times[m].wall:.2f} s, {times[m].cpu:.2f} CPU-s",
              h.ratios([times[m]], [times["ideal"]], "cpu") if m != "ideal" else None,
              "CPU ÷ the ideal simulation's" if m != "ideal" else "")
