"""Interference checks on IPAnema 3's wrench-feasible workspace: what survives, and their cost.

Prints (1) how much of the wrench-feasible workspace survives the interference checks, by kind,
and (2) the checks' cost in the sweep, as time factors against the plain point-outlet sweep in the
same rounds (warm; the first calls load or compile numba's cache, reported too).
"""

from __future__ import annotations

import numpy as np

from benchmarks import harness as h

OPTIONS = {"step": 0.2, "diameter": None}
QUICK = {"step": 0.3}


def evaluator(design, kind: str, collisions: bool):
    """The explicit-position evaluator of the design's robot for ``kind``, with or without the checks."""
    from cdpr_design.statics.robot import Analysis, resolve
    from cdpr_design.workspaces.hardware import Evaluator

    return Evaluator(resolve(design, Analysis(kind=kind, collisions=collisions)))


def load_ipanema3(diameter=None):
    from cdpr_design.model import spec

    d = spec.load(h.ROOT / "designs" / "ipanema3.yaml")
    if diameter is not None:
        raw = dict(d.raw)
        raw["cable"] = {**raw.get("cable", {}), "diameter": diameter}
        d = spec.from_dict(raw, source=d.source)
    return d


def survival(design, kind, step):
    """Feasible poses and the interference kinds that hit them (full masks)."""
    from cdpr_design import kernels as K
    from cdpr_design import workspaces as ws
    from cdpr_design.statics.interference import HIT_NAMES
    from cdpr_design.workspaces.grid import positions3 as _positions3

    g = ws.make_grid(design, step)
    ev = evaluator(design, kind, True)
    ori = design.default_orientation_full()
    nfeas = 0
    survive = 0
    by_kind = {name: 0 for name in HIT_NAMES.values()}
    only = {name: 0 for name in HIT_NAMES.values()}
    no_eff = 0
    for start in range(0, g.size, ws.CHUNK):
        cnt = min(ws.CHUNK, g.size - start)
        f, _, _, _, mask = ev(_positions3(g, start, cnt), ori)
        f = f.astype(bool)
        nfeas += int(f.sum())
        survive += int((f & (mask == 0)).sum())
        no_eff += int((f & ((mask & ~np.uint8(K.HIT_CABLE_EFFECTOR)) == 0)).sum())
        for bit, name in HIT_NAMES.items():
            hit = f & ((mask & bit) != 0)
            by_kind[name] += int(hit.sum())
            only[name] += int((f & (mask == bit)).sum())
    return g.size, nfeas, survive, by_kind, only, no_eff


def run(b: h.Bench) -> None:
    from cdpr_design import workspaces as ws
    from cdpr_design.statics.interference import HIT_NAMES
    from cdpr_design.workspaces.grid import positions3

    d = load_ipanema3(b.opt["diameter"])
    step = b.opt["step"]
    kind = "wrench-feasible" if d.workspace.external_wrench is not None else "static"
    cold_plain, r_plain = h.timed(ws.run, d, ws.Analysis(kind=kind), step=step, keep_maps=False)
    cold_int, r_int = h.timed(ws.run, d, ws.Analysis(kind=kind, collisions=True), step=step,
                                 keep_maps=False)
    assert r_int.extra["feasible_statics"] == r_plain.feasible
    g = ws.make_grid(d, step)
    ori = d.default_orientation_full()
    P = positions3(g, 0, g.size)
    ev0, ev1 = evaluator(d, kind, False), evaluator(d, kind, True)
    ev0(P[:10], ori)
    ev1(P[:10], ori, full=False)
    t = h.rounds({"plain": lambda: ws.run(d, ws.Analysis(kind=kind), step=step, keep_maps=False),
                  "points": lambda: ev0(P, ori),
                  "first hit": lambda: ev1(P, ori, full=False),
                  "full": lambda: ev1(P, ori, full=True),
                  "run": lambda: ws.run(d, ws.Analysis(kind=kind, collisions=True), step=step, keep_maps=False)}, b.rounds)
    poses, nfeas, surv, by_kind, only, no_eff = survival(d, kind, step)
    b.say(f"{kind}, step {step} m, cable diameter {d.cables[0].props.diameter} m: {poses:,} poses, feasible {nfeas:,} "
          f"({100 * nfeas / poses:.1f} %), interference free {surv:,} ({100 * surv / max(nfeas, 1):.1f} % survive; "
          f"{100 * no_eff / max(nfeas, 1):.1f} % without the cable-effector check)")
    for name in HIT_NAMES.values():
        b.say(f"hit by {name:15s}: {by_kind[name]:7,} ({100 * by_kind[name] / max(nfeas, 1):5.1f} %), "
              f"by it alone {only[name]:7,}")
    label = f"IPAnema 3 {kind}, {poses:,} poses"
    against = "time ÷ the plain point-outlet sweep's"
    for what, key in (("explicit positions, no checks", "points"), ("interference, first-hit exit", "first hit"),
                      ("interference, full masks", "full"), ("workspace.run(Analysis(collisions=True))", "run")):
        b.row(f"{label}: {what}", h.seconds(h.spread(x.wall for x in t[key])), h.ratios(t[key], t["plain"]), against)
    b.say(f"first calls: plain {cold_plain.wall:.2f} s, with interference {cold_int.wall:.2f} s")
