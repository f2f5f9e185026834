#!/usr/bin/env python3
"""Accuracy check: how far the hanging search of a spatial body on four or five cables is
from the least tilted orientation it could hang in.

At a commanded position a body on four taut cables has a one-parameter family
of balanced orientations (the lengths can still choose among them); its
members with every tension >= 0 end where one tension reaches zero, which is a
three-cable answer.  On five cables the family has two parameters, and the
edges of its pulling region are arcs of four-cable families.
:func:`cdpr_design.statics.hanging.at_positions.hanging_orientations` reports the least tilted stable
answer among the ones its search finds: Newton's method for every three taut
cables and for all of them, then marches along the four-cable families from
them (docs/hanging-pose.md).  This script measures, at random
positions inside the middle 80 % of the design's frame, how much more tilted
that answer is than an independent search for the least tilted balanced
orientation with every tension >= 0: scipy SLSQP minimising 1 - cos(tilt)
over (rotation vector, tensions) subject to force and moment balance (scipy's
rotations, its own kinematics) and tensions >= 0, from ``--starts`` random
starts per position.  SLSQP is not a global method either: a position where
the library's answer is the less tilted one is counted apart.  Stability is
not checked by the reference (it is for the library's answer), so the
reference can only be less tilted, never wrongly more.

Prints, for the design's mass and for ``--mass`` if given: the positions
where the library is more tilted than the reference by more than
``--tol`` degrees, the largest such gap, the positions where it is less
tilted, and how many of the reference's answers have every cable
pulling.  A less tilted reference orientation turned more than 90 degrees
about the vertical (the body's cables then cross; the search starts there only
where nothing else balances) is counted apart.  Takes about 1.5 s a position.

Usage:  python scripts/check_hanging_least_tilt.py [designs/crane4.yaml] [--n 60] [--seed 5]
        [--starts 16] [--mass 0.5] [--tol 0.01]
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from cdpr_design.model.spec import load
from cdpr_design.statics import hanging as H
from cdpr_design.statics.hanging.at_positions import hanging_orientations
from cdpr_design.statics.hanging.geometry import Geometry


def least_tilt_reference(A, B, c, mass, g, p, starts: int, rng) -> tuple[float, np.ndarray | None, np.ndarray]:
    """(least tilt [deg], its rotation, its tensions [N]) over SLSQP runs from random starts
    (``rng``), each minimising 1 - cos(tilt) over (rotation vector, tensions) subject to force
    and moment balance and tensions >= 0; (inf, None, nan) when no run ends balanced with
    tensions >= 0.  Not a global method: it can miss orientations, never invent one.  (The
    tests use it too.)"""
    f = mass * g
    up = -g / np.linalg.norm(g)
    weight = mass * float(np.linalg.norm(g))
    size = max(float(np.max(np.linalg.norm(B - B.mean(0), axis=1))), 1e-3)

    def balance(x):
        R = Rotation.from_rotvec(x[:3]).as_matrix()
        Rb = B @ R.T
        l = A - p - Rb
        u = l / np.linalg.norm(l, axis=1)[:, None]
        return np.concatenate([u.T @ x[3:] + f, (np.cross(Rb, u).T @ x[3:] + np.cross(R @ c, f)) / size]) / weight

    def one_minus_cos_tilt(x):
        return 1.0 - Rotation.from_rotvec(x[:3]).as_matrix() @ up @ up

    best, rotation, tensions = math.inf, None, np.full(len(A), np.nan)
    for _ in range(starts):
        x0 = np.concatenate([rng.normal(size=3) * 0.4, rng.uniform(0.0, 2.0 * weight / len(A), len(A))])
        r = minimize(one_minus_cos_tilt, x0, method="SLSQP", bounds=[(None, None)] * 3 + [(0.0, None)] * len(A),
                     constraints=[{"type": "eq", "fun": balance}], options={"ftol": 1e-12, "maxiter": 400})
        if not (np.abs(balance(r.x)).max() < 1e-9 and np.all(r.x[3:] >= -1e-9 * weight)):
            continue
        R = Rotation.from_rotvec(r.x[:3]).as_matrix()
        v = R @ up
        tilt = math.degrees(math.atan2(np.linalg.norm(np.cross(v, up)), v @ up))
        if tilt < best:
            best, rotation, tensions = tilt, R, r.x[3:].copy()
    return best, rotation, tensions


def half_turned(R, g) -> bool:
    """Whether rotation R (3, 3) turns the body more than 90 deg about the vertical (-g) from
    the level orientation: a horizontal direction of the body points the other way, and its
    cables cross (the search looks for such orientations only where nothing else balances)."""
    up = -np.asarray(g, float) / np.linalg.norm(g)
    e = np.eye(3)[int(np.argmin(np.abs(up)))]
    e = e - (e @ up) * up
    e /= np.linalg.norm(e)
    return bool((R @ e) @ e < 0.0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("design", nargs="?", default="designs/crane4.yaml")
    ap.add_argument("--n", type=int, default=60, help="random positions")
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--starts", type=int, default=16, help="SLSQP starts per position")
    ap.add_argument("--mass", type=float, default=None, help="also run the library at this mass [kg]")
    ap.add_argument("--tol", type=float, default=0.01, help="a gap counts above this [deg]")
    args = ap.parse_args(argv)
    design = load(args.design)
    A, B, c, mass, g, planar = H.design_arrays(design)
    if planar or len(A) not in (4, 5):
        print("this check is for spatial bodies on four or five cables", file=sys.stderr)
        return 2
    lo, hi = np.asarray(design.frame_lower, float), np.asarray(design.frame_upper, float)
    rng = np.random.default_rng(args.seed)
    P = lo + (hi - lo) * (0.1 + 0.8 * rng.random((args.n, 3)))
    t0 = time.perf_counter()
    ref = [least_tilt_reference(A, B, c, mass, g, p, args.starts, np.random.default_rng(args.seed + 1 + i))
           for i, p in enumerate(P)]
    tilt_ref = np.array([r[0] for r in ref])
    turned = np.array([r[1] is not None and half_turned(r[1], g) for r in ref])
    every = sum(bool(np.all(r[2] > 1e-6 * mass * np.linalg.norm(g))) for r in ref)
    print(f"{design.name}: {args.n} positions (seed {args.seed}), reference {time.perf_counter() - t0:.0f} s; "
          f"the reference's least tilted answer has every cable pulling at {every}")
    for m in [mass] + ([args.mass] if args.mass is not None else []):
        h = hanging_orientations(Geometry(A, B, c, m, g), P, False)
        gap = h.tilt_deg - tilt_ref
        both = np.isfinite(gap)
        worse = both & (gap > args.tol)
        print(f"  library at {m:g} kg: more tilted than the reference by > {args.tol:g} deg at {worse.sum()} "
              f"(at {np.sum(worse & turned)} of them the reference's orientation is turned more than 90 deg about "
              f"the vertical), by up to {np.max(gap[both], initial=0.0):.3g} deg; "
              f"less tilted at {np.sum(both & (gap < -args.tol))}; "
              f"feasible only in the library {np.sum(np.isfinite(h.tilt_deg) & ~np.isfinite(tilt_ref))}, "
              f"only in the reference {np.sum(~np.isfinite(h.tilt_deg) & np.isfinite(tilt_ref))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
