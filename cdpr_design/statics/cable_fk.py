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
from cdpr_design.model.limits import lengths_problem
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.robot import Robot

#: Largest accepted residuals: closure [m] and equilibrium [N] (relative to the load + 1 N).
LENGTH_TOL = 1e-9
FORCE_TOL = 1e-9


@dataclass
class CableFK:
    """Pose (motion coords), tensions at the effector and at the outlet [N] (0 when slack),
    ``slack`` cable names, and the residuals: closure [m] and equilibrium [N].  For an
    effector that hangs freely, ``orientation`` (phi [rad] planar, [rx, ry, rz] [rad]
    spatial) and ``tilt`` [deg] of the orientation it comes to rest in (else None)."""

    pose: np.ndarray
    tensions: np.ndarray
    outlet_tensions: np.ndarray
    slack: list
    length_residual: float
    force_residual: float
    method: str = "levenberg-marquardt (catenary closure + equilibrium)"
    orientation: object = None
    tilt: float | None = None


@dataclass(frozen=True)
class _Unknowns:
    """Where the unknown pose coordinates go in the full pose [x, y, z, rx, ry, rz] and the
    wrench rows balanced: the motion's, or every position and orientation coordinate of the
    plane or space for an effector that hangs freely (its orientation is not commanded)."""

    index: tuple
    rows: tuple
    free: bool

    def full(self, design: Design, x) -> np.ndarray:
        if not self.free:
            return design.full_pose(x)
        out = np.zeros(6)
        out[list(self.index)] = x
        return out


def _unknowns(robot: Robot) -> _Unknowns:
    """The pose coordinates solved for and the wrench rows balanced: a hanging effector also
    finds its orientation (every rotation), others the motion's coordinates."""
    design = robot.design
    if robot.orientation.free:
        idx = (0, 1, 5) if design.motion.planar else tuple(range(6))
        return _Unknowns(idx, idx, True)
    return _Unknowns(tuple(design.motion.pose_index), tuple(design.motion.wrench_rows), False)


def _cable_frames(design: Design, full, up):
    """Per cable: X, Z [m], horizontal unit vector (m, 3) and R b (m, 3) at a full pose."""
    Rb = design.attachments @ kin.rotation_matrix(*full[3:]).T
    lvec = design.outlets - full[:3] - Rb
    Z = lvec @ up
    h = lvec - Z[:, None] * up
    X = np.linalg.norm(h, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        uh = np.where(X[:, None] > 1e-14, h / X[:, None], 0.0)
    return X, Z, uh, Rb


def _gravity(design: Design, full) -> np.ndarray:
    """The full wrench [N, N m] of gravity about the platform origin at a full pose."""
    f = design.effector.mass * np.asarray(design.gravity, float)
    c = kin.rotation_matrix(*full[3:]) @ np.asarray(design.effector.center_of_mass, float)
    return np.concatenate([f, np.cross(c, f)])


def _residual(x, design: Design, L0, arr, taut, wscale, unk: _Unknowns):
    from cdpr_design.kernels.catenary import catenary_ends

    n = len(unk.index)
    full = unk.full(design, x[:n])
    idx = np.flatnonzero(taut)
    H, VB = x[n:n + idx.size], x[n + idx.size:]
    X, Z, uh, Rb = _cable_frames(design, full, arr.up)
    res = []
    wrench = _gravity(design, full)
    for k, i in enumerate(idx):
        xc, zc = catenary_ends(abs(H[k]), VB[k], L0[i], arr.w[i], arr.EA[i])
        res += [(xc - X[i]) / max(L0[i], 1e-3), (zc - Z[i]) / max(L0[i], 1e-3)]
        F = abs(H[k]) * uh[i] + VB[k] * arr.up
        wrench += np.concatenate([F, np.cross(Rb[i], F)])
    return np.concatenate([np.asarray(res), wrench[list(unk.rows)] / wscale])


def _start(design: Design, L0, guess, unk: _Unknowns):
    """A start: the unknown pose coordinates, tensions [N] (m,) and the cables the start leaves
    slack.  For an effector that hangs freely, where it rests on ideal cables of the lengths
    L0 (:func:`cdpr_design.statics.hanging.equilibrium`), when they reach; else the
    straight-cable pose of the lengths and its minimum-norm tensions (or a positive guess)."""
    from cdpr_design.statics.tension import min_norm_above

    if unk.free:
        from cdpr_design.statics import hanging as H

        try:
            options = {"nominal": kin.pose_rotation(design, guess)} if guess is not None else {}
            e = H.equilibrium(design, L0, **options)
        except InputError:
            e = None
        if e is not None:
            ori = np.atleast_1d(np.asarray(e.orientation, float))
            slack = np.zeros(design.m, bool)
            slack[list(e.slack)] = True
            return np.concatenate([e.position, ori]), np.maximum(e.tensions, 1e-3), slack
    fk = kin.forward_kinematics(design, L0, guess=guess)
    W = kin.structure_matrix(design, fk.pose)
    t = min_norm_above(W, -kin.gravity_wrench(design, fk.pose), np.zeros(design.m))
    if t is None:
        t = np.full(design.m, design.effector.mass * np.linalg.norm(design.gravity) / max(design.m, 1))
    x = np.asarray(fk.pose, float)
    if unk.free:  # the position, at the nominal orientation
        full = design.full_pose(fk.pose)
        x = full[list(unk.index)]
    return x, np.maximum(t, 1e-3), np.zeros(design.m, bool)


#: A slack cable's chord may exceed its unstretched length by this much (relative) [-].
SLACK_TOL = 1e-12


def forward(robot: Robot, unstretched, guess=None) -> CableFK:
    """The pose [m, rad] of a robot with elastic or sagging cables of unstretched lengths ``unstretched`` [m].

    The effector's force and moment balance (every row of its motion; an effector that
    hangs freely, ``effector.orientation: free``, also finds its orientation from the
    moment balance).  A weightless cable whose chord is shorter than its length is slack
    (no force); no cable is ever reported slack while its chord is longer than its length.
    Raises :class:`InputError` naming ``--lengths`` when no equilibrium is found
    (the residuals say how far the best attempt was).  ``robot``: the design resolved for ``fk``
    (:func:`~cdpr_design.statics.robot.resolve`; refused: the cables below run from point outlets).
    """
    from scipy.optimize import least_squares

    design = robot.design
    if robot.cables.rigid:
        raise InputError("cable model 'ideal': the forward kinematics of straight cables is kinematics.forward_kinematics")
    L0 = np.asarray(unstretched, float).reshape(-1)
    if L0.size != design.m:
        raise InputError(f"--lengths: expected {design.m} unstretched lengths [m], got {L0.size}")
    why = lengths_problem(L0, positive=True)
    if why:
        raise InputError(f"--lengths: unstretched {why}")
    arr = robot.cable
    unk = _unknowns(robot)
    n = len(unk.index)
    p0, t0, slack0 = _start(design, L0, guess, unk)
    X, Z, _, _ = _cable_frames(design, unk.full(design, p0), arr.up)
    chord = np.hypot(X, Z)
    ch = np.where(chord > 0, X / np.maximum(chord, 1e-300), 0.0)
    H0, V0 = t0 * ch, t0 * np.where(chord > 0, Z / np.maximum(chord, 1e-300), 1.0)
    # cables the start leaves slack begin outside the equations if they can be slack (weightless)
    taut = ~(slack0 & (arr.w == 0))
    wscale = 1.0 + design.effector.mass * float(np.linalg.norm(design.gravity))
    tried = set()
    for _ in range(2 * design.m + 2):
        tried.add(taut.tobytes())
        x0 = np.concatenate([p0, H0[taut], V0[taut]])
        sol = least_squares(_residual, x0, jac=kin.forward_difference_jacobian(_residual),
                            args=(design, L0, arr, taut, wscale, unk), method="lm",
                            xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=200 * (x0.size + 1))
        k = int(taut.sum())
        p0 = sol.x[:n]
        H0[taut], V0[taut] = np.abs(sol.x[n:n + k]), sol.x[n + k:]
        X, Z, _, _ = _cable_frames(design, unk.full(design, p0), arr.up)
        chord = np.hypot(X, Z)
        # a slack cable longer than its chord: it is stretched, so it pulls
        stretched = ~taut & (chord > L0 * (1.0 + SLACK_TOL))
        if _converged(sol.fun, L0, taut, wscale) and not stretched.any():
            break
        nxt = taut | stretched
        if not stretched.any():  # not converged: leave out the weightless cables shorter than their chords
            nxt = taut & ~((arr.w == 0) & (chord < L0))
        if nxt.tobytes() in tried:
            break
        new = nxt & ~taut
        # a cable that joins starts at the tension its stretch there gives (a small one where it is
        # not stretched): from 1e-3 N a just taut stiff cable's balance stalled off its root
        with np.errstate(invalid="ignore"):
            t_new = np.maximum(np.nan_to_num(arr.EA * (chord - L0) / L0, posinf=1e-3), 1e-3)
        H0[new] = (t_new * X / np.maximum(chord, 1e-300))[new]
        V0[new] = (t_new * Z / np.maximum(chord, 1e-300))[new]
        taut = nxt
    return _result(design, sol.fun, p0, H0[taut], V0[taut], L0, arr, taut, wscale, unk)


def _residuals(fun, L0, taut, wscale) -> tuple:
    """(closure [m], equilibrium [N]) residuals of a solve."""
    idx = np.flatnonzero(taut)
    nres = 2 * idx.size
    length_res = float(np.max(np.abs(fun[:nres]) * np.maximum(L0[idx].repeat(2), 1e-3))) if nres else 0.0
    force_res = float(np.max(np.abs(fun[nres:])) * wscale) if fun.size > nres else 0.0
    return length_res, force_res


def _converged(fun, L0, taut, wscale) -> bool:
    length_res, force_res = _residuals(fun, L0, taut, wscale)
    return length_res <= LENGTH_TOL and force_res <= FORCE_TOL * wscale


def _result(design: Design, fun, x, H, VB, L0, arr, taut, wscale, unk: _Unknowns) -> CableFK:
    from cdpr_design.statics.hanging.results import orientation_of, tilt_of

    idx = np.flatnonzero(taut)
    length_res, force_res = _residuals(fun, L0, taut, wscale)
    full = unk.full(design, x)
    X, Z, _, _ = _cable_frames(design, full, arr.up)
    over = ~taut & (np.hypot(X, Z) > L0 * (1.0 + SLACK_TOL))
    if over.any():  # never a pose where a cable with no force spans more than its length
        length_res = max(length_res, float(np.max(np.hypot(X, Z)[over] - L0[over])))
    if not (length_res <= LENGTH_TOL and force_res <= FORCE_TOL * wscale):
        raise InputError(f"--lengths: no equilibrium with these unstretched lengths (best attempt: closure "
                         f"residual {length_res:.3g} m, force residual {force_res:.3g} N)")
    t_eff = np.zeros(design.m)
    t_out = np.zeros(design.m)
    t_eff[idx] = np.hypot(H, VB)
    t_out[idx] = np.hypot(H, VB + arr.w[idx] * L0[idx])
    names = [design.cable_names[i] for i in np.flatnonzero(~taut)]
    if not unk.free:
        return CableFK(np.asarray(x, float), t_eff, t_out, names, length_res, force_res)
    R = kin.rotation_matrix(*full[3:])
    pose = full[list(design.motion.pose_index)]
    return CableFK(pose, t_eff, t_out, names, length_res, force_res,
                   orientation=orientation_of(R, design.motion.planar), tilt=tilt_of(R, arr.up))
