"""Benchmark and figures: interference checks on the IPAnema 3 wrench-feasible workspace.

Prints (1) how much of the wrench-feasible workspace survives the interference
checks, by kind, and (2) the speed cost of the checks in the sweep, as ratios
against the plain point-outlet sweep measured in the same process (warm, after
a first call that loads or compiles the numba cache; the cold first call is
reported too).

Usage:  python scripts/bench_interference.py [--step 0.2] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from cdpr_design import kernels as K  # noqa: E402
from cdpr_design.model import spec  # noqa: E402
from cdpr_design import workspaces as ws  # noqa: E402
from cdpr_design.workspaces.hardware import Evaluator
from cdpr_design.workspaces.grid import positions3 as _positions3  # noqa: E402
from cdpr_design.statics.interference import HIT_NAMES  # noqa: E402


def load_ipanema3(diameter=None):
    path = os.path.join(os.path.dirname(__file__), "..", "designs", "ipanema3.yaml")
    d = spec.load(path)
    if diameter is not None:
        raw = dict(d.raw)
        raw["cable"] = {**raw.get("cable", {}), "diameter": diameter}
        d = spec.from_dict(raw, source=d.source)
    return d


def timed(fn, repeat):
    best = np.inf
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def survival(design, kind, step):
    """Feasible poses and the interference kinds that hit them (full masks)."""
    g = ws.make_grid(design, step)
    ev = Evaluator(design, kind, True)
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


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--step", type=float, default=0.2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--diameter", type=float, default=None, help="cable diameter [m] (default: the spec's)")
    args = ap.parse_args()
    d = load_ipanema3(args.diameter)
    kind = "wrench-feasible" if d.workspace.external_wrench is not None else "static"
    print(f"IPAnema 3 ({d.source}), {kind} workspace, step {args.step} m, "
          f"effector box {d.effector.size} m, cable diameter {d.cables[0].props.diameter} m")

    # cold: first calls in this process (numba cache load or compile)
    t0 = time.perf_counter()
    ws.run(d, kind=kind, step=args.step, keep_maps=False)
    cold_plain = time.perf_counter() - t0
    t0 = time.perf_counter()
    ws.run(d, kind=kind, step=args.step, keep_maps=False, interference=True)
    cold_int = time.perf_counter() - t0

    t_plain, r_plain = timed(lambda: ws.run(d, kind=kind, step=args.step, keep_maps=False), args.repeat)
    t_int, r_int = timed(lambda: ws.run(d, kind=kind, step=args.step, keep_maps=False, interference=True),
                         args.repeat)
    # the pulley/interference kernel without the checks: cost of the explicit-position path itself
    g = ws.make_grid(d, args.step)
    ori = d.default_orientation_full()
    P = _positions3(g, 0, g.size)
    ev0 = Evaluator(d, kind, False)
    ev1 = Evaluator(d, kind, True)
    ev0(P[:10], ori)
    ev1(P[:10], ori, full=False)
    t_points, _ = timed(lambda: ev0(P, ori), args.repeat)
    t_first, _ = timed(lambda: ev1(P, ori, full=False), args.repeat)
    t_full, _ = timed(lambda: ev1(P, ori, full=True), args.repeat)

    poses, nfeas, surv, by_kind, only, no_eff = survival(d, kind, args.step)
    print(f"\nposes {poses:,}; wrench-feasible {nfeas:,} ({100 * nfeas / poses:.1f} %)")
    print(f"  interference free among them: {surv:,} ({100 * surv / max(nfeas, 1):.1f} % survive)")
    print(f"  without the cable-effector check:  {no_eff:,} ({100 * no_eff / max(nfeas, 1):.1f} % survive)")
    for name in HIT_NAMES.values():
        print(f"  hit by {name:15s}: {by_kind[name]:7,} ({100 * by_kind[name] / max(nfeas, 1):5.1f} %), "
              f"by it alone {only[name]:7,}")
    assert r_int.extra["feasible_statics"] == r_plain.feasible
    print("\nsweep time (best of %d, warm)              s     ratio" % args.repeat)
    print(f"  plain point-outlet sweep (baseline)  {t_plain:8.3f}   1.00")
    print(f"  explicit positions, no checks        {t_points:8.3f}   {t_points / t_plain:.2f}")
    print(f"  + interference, first-hit exit       {t_first:8.3f}   {t_first / t_plain:.2f}")
    print(f"  + interference, full masks           {t_full:8.3f}   {t_full / t_plain:.2f}")
    print(f"  workspace.run(interference=True)     {t_int:8.3f}   {t_int / t_plain:.2f}")
    print(f"cold first call: plain {cold_plain:.2f} s, with interference {cold_int:.2f} s")


if __name__ == "__main__":
    main()
