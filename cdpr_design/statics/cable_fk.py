"""Forward kinematics with elastic or sagging cables: the pose for given unstretched lengths.

Unknowns: the pose (n motion coordinates) and each taut cable's end forces
(H, VB) [N]; equations: each cable's elastic-catenary closure (its end points
X, Z [m] from (H, VB, L0), :func:`cdpr_design.kernels.catenary.catenary_ends`)
and the effector's equilibrium (n rows).  The system is square for any number
of cables.  It is solved by Levenberg-Marquardt from the straight-cable pose
of the same lengths and its tensions, with an active set for weightless
cables: one whose chord is not longer than its unstretched length is slack
(no force) and leaves the equations.  A heavy cable is never slack: it hangs.
The answer is checked: a residual above tolerance, or a cable that would have
to push, is an error, never a pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design.errors import InputError
from cdpr_design.model.design import Design
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.cables import cable_arrays, design_model

#: Largest accepted residuals: closure [m] and equilibrium [N] (relative to the load + 1 N).
LENGTH_TOL = 1e-9
FORCE_TOL = 1e-9


@dataclass
class CableFK:
    """Pose (motion coords), tensions at the effector and at the outlet [N] (0 when slack),
    ``slack`` cable names, and the residuals: closure [m] and equilibrium [N]."""

    pose: np.ndarray
    tensions: np.ndarray
    outlet_tensions: np.ndarray
    slack: list
    length_residual: float
    force_residual: float
    method: str = "levenberg-marquardt (catenary closure + equilibrium)"


def _cable_frames(design: Design, pose, up):
    """Per cable: X, Z [m], horizontal unit vector (m, 3) and R b (m, 3) at a pose."""
    full = design.full_pose(pose)
    Rb = design.attachments @ kin.rotation_matrix(*full[3:]).T
    lvec = design.outlets - full[:3] - Rb
    Z = lvec @ up
    h = lvec - Z[:, None] * up
    X = np.linalg.norm(h, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        uh = np.where(X[:, None] > 1e-14, h / X[:, None], 0.0)
    return X, Z, uh, Rb


def _residual(x, design: Design, L0, arr, taut, wscale):
    from cdpr_design.kernels.catenary import catenary_ends

    n = design.n
    pose = x[:n]
    idx = np.flatnonzero(taut)
    H, VB = x[n:n + idx.size], x[n + idx.size:]
    X, Z, uh, Rb = _cable_frames(design, pose, arr.up)
    rows = list(design.motion.wrench_rows)
    res = []
    wrench = kin.gravity_wrench(design, pose).astype(float)
    for k, i in enumerate(idx):
        xc, zc = catenary_ends(abs(H[k]), VB[k], L0[i], arr.w[i], arr.EA[i])
        res += [(xc - X[i]) / max(L0[i], 1e-3), (zc - Z[i]) / max(L0[i], 1e-3)]
        F = abs(H[k]) * uh[i] + VB[k] * arr.up
        wrench += np.concatenate([F, np.cross(Rb[i], F)])[rows]
    return np.concatenate([np.asarray(res), wrench / wscale])


def _start(design: Design, L0, guess):
    """The straight-cable pose of the lengths and its minimum-norm tensions (or a positive guess)."""
    from cdpr_design.statics.tension import min_norm_above

    fk = kin.forward_kinematics(design, L0, guess=guess)
    W = kin.structure_matrix(design, fk.pose)
    t = min_norm_above(W, -kin.gravity_wrench(design, fk.pose), np.zeros(design.m))
    if t is None:
        t = np.full(design.m, design.effector.mass * np.linalg.norm(design.gravity) / max(design.m, 1))
    return fk.pose, np.maximum(t, 1e-3)


def forward(design: Design, unstretched, guess=None) -> CableFK:
    """The pose [m, rad] of a design with elastic or sagging cables of unstretched lengths ``unstretched`` [m].

    Raises :class:`InputError` naming ``--lengths`` when no equilibrium is found
    (the residuals say how far the best attempt was).
    """
    from scipy.optimize import least_squares

    model = design_model(design)
    if model == "ideal":
        raise InputError("cable model 'ideal': the forward kinematics of straight cables is kinematics.forward_kinematics")
    if kin.has_pulleys(design):  # the cables below run from point outlets
        raise InputError(f"cable model {model!r}: the forward kinematics of elastic and sagging cables takes point "
                         "outlets, not swivel pulleys; use --cable-model ideal for this design")
    L0 = np.asarray(unstretched, float).reshape(-1)
    if L0.size != design.m or not np.all(np.isfinite(L0)) or np.any(L0 <= 0):
        raise InputError(f"--lengths: expected {design.m} positive unstretched lengths [m], got {list(L0)}")
    arr = cable_arrays(design)
    p0, t0 = _start(design, L0, guess)
    X, Z, uh, _ = _cable_frames(design, p0, arr.up)
    chord = np.hypot(X, Z)
    ch = np.where(chord > 0, X / np.maximum(chord, 1e-300), 0.0)
    H0, V0 = t0 * ch, t0 * np.where(chord > 0, Z / np.maximum(chord, 1e-300), 1.0)
    taut = np.ones(design.m, dtype=bool)
    wscale = 1.0 + design.effector.mass * float(np.linalg.norm(design.gravity))
    for _ in range(design.m + 1):
        x0 = np.concatenate([p0, H0[taut], V0[taut]])
        sol = least_squares(_residual, x0, args=(design, L0, arr, taut, wscale), method="lm",
                            xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=200 * (x0.size + 1))
        n, k = design.n, int(taut.sum())
        p0 = sol.x[:n]
        H0[taut], V0[taut] = np.abs(sol.x[n:n + k]), sol.x[n + k:]
        X, Z, _, _ = _cable_frames(design, p0, arr.up)
        slack_now = taut & (arr.w == 0) & (np.hypot(X, Z) <= L0)
        if not slack_now.any():
            break
        taut &= ~slack_now
    return _result(design, sol.fun, p0, H0[taut], V0[taut], L0, arr, taut, wscale)


def _result(design: Design, fun, pose, H, VB, L0, arr, taut, wscale) -> CableFK:
    idx = np.flatnonzero(taut)
    nres = 2 * idx.size
    length_res = float(np.max(np.abs(fun[:nres]) * np.maximum(L0[idx].repeat(2), 1e-3))) if nres else 0.0
    force_res = float(np.max(np.abs(fun[nres:])) * wscale) if fun.size > nres else 0.0
    if not (length_res <= LENGTH_TOL and force_res <= FORCE_TOL * wscale):
        raise InputError(f"--lengths: no equilibrium with these unstretched lengths (best attempt: closure "
                         f"residual {length_res:.3g} m, force residual {force_res:.3g} N)")
    t_eff = np.zeros(design.m)
    t_out = np.zeros(design.m)
    t_eff[idx] = np.hypot(H, VB)
    t_out[idx] = np.hypot(H, VB + arr.w[idx] * L0[idx])
    names = [design.cable_names[i] for i in np.flatnonzero(~taut)]
    return CableFK(np.asarray(pose, float), t_eff, t_out, names, length_res, force_res)
