#!/usr/bin/env python3
"""Benchmark: crane4's hanging orientations, the batched search against per-position scipy.

crane4 (a 60 kg load on four cables, ``effector.orientation: free``) is
found hanging from three of its cables or all four; at each position of its 0.25 m
grid (2,873 positions) the library finds the least tilted stable orientation
with every cable pulling (:func:`cdpr_design.statics.hanging.at_positions.hanging_orientations`: batched
numpy Newton per set of taut cables, a march along the four-cable family, then the
stability of the candidates).
This times

* the whole ``free`` workspace sweep (:func:`cdpr_design.workspaces.run`:
  orientation, then feasibility, margin and tensions there), on one thread and
  on the kernels' threads (best of ``--repeat``);
* ``hang`` alone on the grid, one thread;
* a plain per-position scipy solve on a random subsample, in the same process:
  for each set of three taut cables, ``scipy.optimize.least_squares`` on force
  and moment balance (rotation vector and tensions, scipy's rotations) from
  ``--starts`` starting orientations; the distinct pulling answers kept; stable
  when the smallest eigenvalue of the finite-difference Hessian of
  U + sum t_i |l_i| on the tangent space of the taut lengths is positive; the
  least tilted stable one wins - the library's rule.

Prints the times per position, the ratios to scipy, and how well the two
agree on the subsample (status, tilt) where the library's answer hangs from
three cables: where all four pull, their balanced orientations form a family
(the library marches along it to its least tilted pulling member,
docs/hanging-pose.md), and this baseline, which solves three-cable sets only,
then finds a more tilted three-cable answer or none.

Usage:  python scripts/bench_hanging_spatial.py [--n-scipy 30] [--starts 8] [--repeat 3]
"""

from __future__ import annotations

import argparse
import itertools
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from scipy.linalg import null_space  # noqa: E402
from scipy.optimize import least_squares  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

from cdpr_design import workspaces as ws  # noqa: E402
from cdpr_design.kernels import parallel  # noqa: E402
from cdpr_design.model import spec  # noqa: E402
from cdpr_design.statics import hanging as H  # noqa: E402
from cdpr_design.statics.hanging.at_positions import hanging_orientations  # noqa: E402
from cdpr_design.statics.hanging.geometry import Geometry  # noqa: E402
from cdpr_design.statics.hanging.results import OK  # noqa: E402
from cdpr_design.workspaces.grid import positions3  # noqa: E402

DESIGN = os.path.join(os.path.dirname(__file__), "..", "designs", "crane4.yaml")


def scipy_hanging(A, B, c, mass, g, p, starts, size):
    """(tilt [deg] or None) of the least tilted stable pulling orientation at p, per-position scipy;
    ``size`` [m] scales the moments (the effector's length scale)."""
    f = mass * g
    weight = mass * np.linalg.norm(g)
    up = -g / np.linalg.norm(g)
    best = None
    for S in itertools.combinations(range(len(A)), 3):
        S = list(S)

        def residual(x):
            R = Rotation.from_rotvec(x[:3]).as_matrix()
            Rb = B[S] @ R.T
            l = A[S] - p - Rb
            u = l / np.linalg.norm(l, axis=1)[:, None]
            return np.concatenate([u.T @ x[3:] + f, (np.cross(Rb, u).T @ x[3:] + np.cross(R @ c, f)) / size]) / weight

        found = []
        for w0 in starts:
            s = least_squares(residual, np.concatenate([w0, np.full(3, weight / 3)]), xtol=1e-15, ftol=1e-15,
                              gtol=1e-15)
            if np.max(np.abs(s.fun)) > 1e-10 or s.x[3:].min() < -1e-9 * weight:
                continue
            R = Rotation.from_rotvec(s.x[:3]).as_matrix()
            if any(np.linalg.norm(R - Q) < 1e-6 for Q in found):
                continue
            found.append(R)
            t = np.zeros(len(A))
            t[S] = s.x[3:]
            if _stable(A, B, c, mass, g, p, R, t, S):
                tilt = math.degrees(math.acos(np.clip(up @ R @ up, -1.0, 1.0)))
                best = tilt if best is None else min(best, tilt)
    return best


def _stable(A, B, c, mass, g, p, R, t, S, h=1e-4):
    """Smallest eigenvalue of the finite-difference Hessian of U + sum t |l| on the tangent space
    of the taut lengths (positions and rotation vectors about R) > 0."""
    def conf(x):
        return p + x[:3], Rotation.from_rotvec(x[3:]).as_matrix() @ R

    def lag(x):
        q, Q = conf(x)
        return -mass * g @ (q + Q @ c) + t @ np.linalg.norm(A - q - B @ Q.T, axis=1)

    def lengths(x):
        q, Q = conf(x)
        return np.linalg.norm(A[S] - q - B[S] @ Q.T, axis=1)

    E = np.eye(6) * h
    Hm = np.array([[(lag(E[i] + E[j]) - lag(E[i] - E[j]) - lag(E[j] - E[i]) + lag(-E[i] - E[j])) / (4 * h * h)
                    for j in range(6)] for i in range(6)])
    G = np.array([(lengths(E[j]) - lengths(-E[j])) / (2 * h) for j in range(6)]).T
    N = null_space(G)
    # above the finite differences' noise (the library's own margin is 1e-9 of the weight)
    return float(np.linalg.eigvalsh(N.T @ Hm @ N)[0]) > 1e-6 * mass * np.linalg.norm(g)


def best_of(repeat, fn):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-scipy", type=int, default=30, help="positions solved by scipy (random subsample)")
    ap.add_argument("--starts", type=int, default=8, help="scipy's starting orientations per set of taut cables")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()

    d = spec.load(DESIGN)
    g = ws.make_grid(d)
    P = positions3(g, 0, g.size)
    A, B, c, mass, grav, planar = H.design_arrays(d)
    geo = Geometry(A, B, c, mass, grav)
    ws.run(d, grid=ws.first_pose(g))  # numba's kernels loaded, the numpy paths warm

    with parallel.threads_kept():
        parallel.set_threads(1)
        t_hang, got = best_of(a.repeat, lambda: hanging_orientations(geo, P, False))
        t_one, _ = best_of(a.repeat, lambda: ws.run(d, grid=g))
    t_all, _ = best_of(a.repeat, lambda: ws.run(d, grid=g))
    threads = parallel.threads()

    rng = np.random.default_rng(1)
    idx = rng.choice(len(P), size=min(a.n_scipy, len(P)), replace=False)
    starts = [np.zeros(3)] + [rng.normal(size=3) * 0.7 for _ in range(a.starts - 1)]
    t0 = time.perf_counter()
    ref = [scipy_hanging(A, B, c, mass, grav, P[i], starts, geo.size) for i in idx]
    per_scipy = (time.perf_counter() - t0) / len(idx)

    n = len(P)
    tilt = got.tilt_deg
    four = np.sum(got.tensions > 1e-9 * geo.weight, axis=1) == 4
    three = [(i, r) for i, r in zip(idx, ref) if not four[i]]
    both = [(tilt[i], r) for i, r in three if r is not None and got.status[i] == OK]
    status_same = sum((r is not None) == (got.status[i] == OK) for i, r in three)
    print(f"crane4, {n:,} positions (0.25 m grid); best of {a.repeat}; scipy on {len(idx)} positions, "
          f"{a.starts} starts per set of three taut cables")
    print(f"  scipy per position                 {1e3 * per_scipy:9.2f} ms")
    for what, t in (("hang(), one thread", t_hang), ("free workspace sweep, one thread", t_one),
                    (f"free workspace sweep, {threads} threads", t_all)):
        print(f"  {what:34s} {t:7.3f} s = {1e3 * t / n:6.3f} ms a position = {per_scipy * n / t:7.0f}x scipy")
    print(f"  agreement where it hangs from three cables ({len(three)} of the {len(idx)}; all four pull at "
          f"the others): status on {status_same}; largest tilt difference "
          f"{max((abs(x - y) for x, y in both), default=float('nan')):.2e} deg over {len(both)}")


if __name__ == "__main__":
    main()
