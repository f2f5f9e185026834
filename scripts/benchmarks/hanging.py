"""planar2's tilt map: the batched numba kernel against a per-position scipy solve.

The hanging orientation of planar2's effector (two cables, free orientation) at every position of
a 151 x 151 grid over its 1.5 m frame (22,801 positions), with
:func:`cdpr_design.statics.hanging.at_positions.hanging_orientations` (the closed form) cold (a new process with an empty numba
cache: compiled) and warm, and with a plain per-position scipy solve on a random subsample in the
same rounds, scaled per position:

    for each start angle in 8 evenly spaced ones, ``scipy.optimize.least_squares`` on force +
    moment balance (unknowns phi, t1, t2; residuals scaled by the weight), the distinct converged
    roots kept; tensions >= 0 and stability (second difference of the energy along the
    constant-length curve) decide; the stable one closest to level wins - the kernel's rule.

The same map also through the library's two other paths, in the same rounds: the numpy
hanging solver (``hanging_orientations``) and the whole ``free``
workspace sweep (:func:`cdpr_design.workspaces.run`).  Prints how well the kernel and scipy
agree (orientation and status on the subsample).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from benchmarks import harness as h

OPTIONS = {"n_scipy": 400, "com_y": None}
QUICK = {"n_scipy": 100}


def scipy_tilt(A, B, c, mass, g, p, starts=8):
    """One position with scipy least_squares from several angles (see module doc)."""
    from scipy.optimize import least_squares

    A2, B2, c2, gv = A[:, :2], B[:, :2], c[:2], g[:2]
    W = mass * float(np.hypot(*gv))

    def rot(phi):
        co, si = math.cos(phi), math.sin(phi)
        return np.array([[co, -si], [si, co]])

    def residual(x):
        phi, t1, t2 = x
        R = rot(phi)
        Rb = B2 @ R.T
        v = A2 - p - Rb
        u = v / np.linalg.norm(v, axis=1)[:, None]
        f = t1 * u[0] + t2 * u[1] + mass * gv
        rc = R @ c2
        mom = sum(t * ((Rb[i, 0] - rc[0]) * u[i, 1] - (Rb[i, 1] - rc[1]) * u[i, 0])
                  for i, t in enumerate((t1, t2)))
        return np.array([f[0], f[1], mom / 0.1]) / W

    def energy_on_curve(phi, rho):
        R = rot(phi)
        C = A2 - B2 @ R.T
        e = C[1] - C[0]
        D = float(np.linalg.norm(e))
        a = (rho[0] ** 2 - rho[1] ** 2 + D ** 2) / (2 * D)
        h = math.sqrt(max(rho[0] ** 2 - a ** 2, 0.0))
        n = np.array([-e[1], e[0]]) / D
        q = min((C[0] + a * e / D + s * h * n for s in (1, -1)), key=lambda q: np.linalg.norm(q - p))
        return -mass * gv @ (q + R @ c2)

    found = []
    for k in range(starts):
        s = least_squares(residual, [-math.pi + 2 * math.pi * k / starts, W / 2, W / 2],
                          xtol=1e-15, ftol=1e-15, gtol=1e-15)
        if np.max(np.abs(s.fun)) > 1e-10:
            continue
        phi = math.atan2(math.sin(s.x[0]), math.cos(s.x[0]))
        if any(abs(phi - f[0]) < 1e-8 for f in found):
            continue
        found.append((phi, s.x[1], s.x[2]))
    best = None
    for phi, t1, t2 in found:
        if min(t1, t2) < -1e-9 * W:
            continue
        rho = np.linalg.norm(A2 - p - B2 @ rot(phi).T, axis=1)
        h = 1e-3
        d2 = energy_on_curve(phi + h, rho) + energy_on_curve(phi - h, rho) - 2 * energy_on_curve(phi, rho)
        if d2 > 0 and (best is None or abs(phi) < abs(best)):
            best = phi
    return best



def problem(com_y=None):
    """planar2's outlets, attachments, centre of mass, mass, gravity and the 151 x 151 positions."""
    from cdpr_design.model import spec

    d = spec.load(h.ROOT / "designs" / "planar2.yaml")
    c = np.asarray(d.effector.center_of_mass, float)
    if com_y is not None:
        c[1] = com_y
    xs = 0.01 * np.arange(151)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    P = np.ascontiguousarray(np.column_stack([X.ravel(), Y.ravel()]))
    return d, (d.outlets, d.attachments, c, float(d.effector.mass), np.asarray(d.gravity, float)), P


def cold(com_y=None) -> float:
    """Seconds of the closed form's first call in this process."""
    _, (A, B, c, mass, g), P = problem(com_y)
    from cdpr_design.statics.hanging.at_positions import hanging_orientations
    from cdpr_design.statics.hanging.geometry import Geometry

    t, _ = h.timed(hanging_orientations, Geometry(A, B, c, mass, g), P, True)
    return t.wall


def run(b: h.Bench) -> None:
    from cdpr_design import workspaces as ws
    from cdpr_design.statics.hanging.at_positions import hanging_orientations
    from cdpr_design.statics.hanging.results import OK
    from cdpr_design.statics.hanging.geometry import Geometry

    t_cold = h.call_in_child("benchmarks.hanging.cold", b.opt["com_y"], cache=b.fresh_cache())
    d, (A, B, c, mass, g), P = problem(b.opt["com_y"])
    n = P.shape[0]
    geo = Geometry(A, B, c, mass, g)
    got = hanging_orientations(geo, P, True)
    phi, status = got.orientation, got.status
    free = d.replace(effector=dataclasses.replace(d.effector, orientation="free", center_of_mass=tuple(c)))
    first_ws, res = h.timed(ws.run, free)
    idx = b.rng.choice(n, size=min(b.opt["n_scipy"], n), replace=False)
    ref = []
    t = h.rounds({"closed form": lambda: hanging_orientations(geo, P, True),
                  "free workspace": lambda: ws.run(free),
                  "scipy": lambda: ref.__setitem__(slice(None), [scipy_tilt(A, B, c, mass, g, P[i]) for i in idx])},
                 b.rounds)
    ok_k = status[idx] == OK
    ok_s = np.array([r is not None for r in ref])
    both = ok_k & ok_s
    diff = np.abs(phi[idx][both] - np.array([r for r in ref if r is not None])[both[ok_s]])
    b.say(f"COM at y = {c[1]:+.3f} m: {n} positions, {np.count_nonzero(status == OK)} hang stably, max tilt "
          f"{np.nanmax(np.degrees(np.abs(phi))):.2f} deg; scipy: status agrees on {np.count_nonzero(ok_k == ok_s)}/"
          f"{idx.size}, max |dphi| {diff.max() if diff.size else float('nan'):.1e} rad; free workspace "
          f"{res.feasible} feasible")
    scale = n / idx.size
    label = f"planar2 tilt map, {n:,} positions"
    b.row(f"{label}: closed form, warm", h.per_pose(h.best(t["closed form"]), n),
          h.ratios(t["scipy"], t["closed form"], scale=scale), "per-position scipy least_squares")
    b.row(f"{label}: closed form, first call in a new process", f"{t_cold:.2f} s",
          h.ratios([h.best(t["scipy"])], [t_cold], scale=scale), "per-position scipy (best round)")
    b.row(f"{label}: the whole free workspace sweep, warm", h.seconds(h.spread(x.wall for x in t["free workspace"])),
          h.ratios(t["scipy"], t["free workspace"], scale=scale), "per-position scipy least_squares",
          f"first call {first_ws.wall:.2f} s")
