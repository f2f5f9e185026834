"""crane4's hanging orientations: the batched search against a per-position scipy solve.

crane4 (a 60 kg load on four cables, ``effector.orientation: free``) is found hanging from three of
its cables or all four; at each position of its 0.25 m grid (2,873 positions) the library finds the
least tilted stable orientation with every cable pulling
(:func:`cdpr_design.statics.hanging.at_positions.hanging_orientations`: batched numpy Newton per set
of taut cables, a march along the four-cable family, then the stability of the candidates).  Timed,
in the same rounds as a plain per-position scipy solve on a random subsample:

* ``hang`` alone on the grid, one thread;
* the whole ``free`` workspace sweep (:func:`cdpr_design.workspaces.run`: orientation, then
  feasibility, margin and tensions there), on one thread and on the kernels' threads;
* scipy: for each set of three taut cables, ``scipy.optimize.least_squares`` on force and moment
  balance (rotation vector and tensions, scipy's rotations) from ``starts`` starting orientations;
  the distinct pulling answers kept; stable when the smallest eigenvalue of the finite-difference
  Hessian of U + sum t_i |l_i| on the tangent space of the taut lengths is positive; the least
  tilted stable one wins - the library's rule.

Prints how well the two agree on the subsample (status, tilt) where the library's answer hangs from
three cables.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.linalg import null_space
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from benchmarks import harness as h

OPTIONS = {"n_scipy": 30, "starts": 8}
QUICK = {"n_scipy": 10}


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


def run(b: h.Bench) -> None:
    from cdpr_design import workspaces as ws
    from cdpr_design.kernels import parallel
    from cdpr_design.model import spec
    from cdpr_design.statics import hanging as H
    from cdpr_design.statics.hanging.at_positions import hanging_orientations
    from cdpr_design.statics.hanging.geometry import Geometry
    from cdpr_design.statics.hanging.results import OK
    from cdpr_design.workspaces.grid import positions3

    d = spec.load(h.ROOT / "designs" / "crane4.yaml")
    g = ws.make_grid(d)
    P = positions3(g, 0, g.size)
    A, B, c, mass, grav, planar = H.design_arrays(d)
    geo = Geometry(A, B, c, mass, grav)
    ws.run(d, grid=ws.first_pose(g))  # numba's kernels loaded, the numpy paths warm
    idx = b.rng.choice(len(P), size=min(b.opt["n_scipy"], len(P)), replace=False)
    starts = [np.zeros(3)] + [b.rng.normal(size=3) * 0.7 for _ in range(b.opt["starts"] - 1)]
    got, ref = {}, []

    def one_thread(fn):
        with parallel.threads_kept():
            parallel.set_threads(1)
            return fn()

    t = h.rounds({"hang": lambda: got.__setitem__("h", one_thread(lambda: hanging_orientations(geo, P, False))),
                  "sweep, one thread": lambda: one_thread(lambda: ws.run(d, grid=g)),
                  "sweep": lambda: ws.run(d, grid=g),
                  "scipy": lambda: ref.__setitem__(slice(None), [scipy_hanging(A, B, c, mass, grav, P[i], starts,
                                                                               geo.size) for i in idx])}, b.rounds)
    n = len(P)
    hung = got["h"]
    four = np.sum(hung.tensions > 1e-9 * geo.weight, axis=1) == 4
    three = [(i, r) for i, r in zip(idx, ref) if not four[i]]
    both = [(hung.tilt_deg[i], r) for i, r in three if r is not None and hung.status[i] == OK]
    same = sum((r is not None) == (hung.status[i] == OK) for i, r in three)
    b.say(f"agreement where it hangs from three cables ({len(three)} of the {len(idx)}): status on {same}; largest "
          f"tilt difference {max((abs(x - y) for x, y in both), default=float('nan')):.2e} deg over {len(both)}")
    scale = n / len(idx)
    for what, key in (("hang(), one thread", "hang"), ("free workspace sweep, one thread", "sweep, one thread"),
                      (f"free workspace sweep, {parallel.threads()} threads", "sweep")):
        b.row(f"crane4, {n:,} positions: {what}", h.per_pose(h.best(t[key]), n).replace("pose", "position"),
              h.ratios(t["scipy"], t[key], scale=scale), f"per-position scipy least_squares ({b.opt['starts']} starts)")
