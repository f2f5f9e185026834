"""What a hanging effector's new combinations cost against its ideal-cable sweep.

For each design (``effector.orientation: free``): the whole workspace sweep as a command runs it
(``workspaces.run``: the plan, its parts, the maps; no files, no boundary), on ideal cables (the
baseline) and with each new combination: elastic and sagging cables, ``--stiffness`` and
``--collisions`` at the hanging orientation.  The variants of a round run back to back in an order
rotated from round to round (:func:`benchmarks.harness.rounds`); CPU on ``threads`` kernel threads;
the median and range of the rounds' own ratios.
"""

from __future__ import annotations

import dataclasses

from benchmarks import harness as h

OPTIONS = {"designs": ("crane4", "planar2"), "threads": 2, "step": None}
QUICK = {"designs": ("crane4",), "step": 0.5}

#: (label, cable model, options of the Analysis) of each variant; the first is the baseline.
VARIANTS = (
    ("ideal", "ideal", {}),
    ("elastic", "elastic", {}),
    ("ideal --stiffness", "ideal", {"stiffness": True}),
    ("elastic --stiffness", "elastic", {"stiffness": True}),
    ("ideal --collisions", "ideal", {"collisions": True}),
    ("elastic --collisions", "elastic", {"collisions": True}),
    ("sagging", "sagging", {}),
    ("sagging --stiffness", "sagging", {"stiffness": True}),
)


def free(design):
    return design.replace(effector=dataclasses.replace(design.effector, orientation="free"))


def run(b: h.Bench) -> None:
    from cdpr_design import workspaces as ws
    from cdpr_design.kernels import parallel
    from cdpr_design.model import spec
    from cdpr_design.statics.robot import Analysis

    designs = {n: free(spec.load(h.ROOT / "designs" / f"{n}.yaml")) for n in b.opt["designs"]}
    step = b.opt["step"]
    with parallel.threads_kept():
        parallel.set_threads(b.opt["threads"])
        for n, d in designs.items():
            models = {m: spec.with_cable_model(d, m) for m in ("ideal", "elastic", "sagging")}
            one = ws.grid.first_pose(ws.make_grid(d))
            for _, m, kw in VARIANTS:  # the kernels compiled or loaded outside the timing
                ws.run(models[m], Analysis(**kw), grid=one)
            variants = {label: (lambda m=m, kw=kw: ws.run(models[m], Analysis(**kw), step=step))
                        for label, m, kw in VARIANTS}
            times = h.rounds(variants, b.rounds)
            poses = ws.make_grid(d, step).size if step else d.workspace.grid.size
            base = times[VARIANTS[0][0]]
            b.row(f"{n} ({poses:,} positions): the hanging sweep on ideal cables",
                  h.seconds(h.spread(t.cpu for t in base)) + " CPU")
            for label, _, _ in VARIANTS[1:]:
                b.row(f"{n}: {label}", h.seconds(h.spread(t.cpu for t in times[label])) + " CPU",
                      h.ratios(times[label], base, "cpu"), f"time ÷ ideal (CPU, {b.opt['threads']} thread(s))")
