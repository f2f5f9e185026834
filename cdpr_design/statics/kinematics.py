"""Inverse and forward kinematics, structure matrix and wrenches (numpy API).

Poses are given in the motion type's own coordinates (``x, y`` for 2T,
``x, y, phi`` for 1R2T, ``x, y, z`` for 3T, ``x, y, z, rx, ry, rz`` for
3R3T).  The vector loop is the paper's equation (1): a_i + l_i = p + R b_i,
here written l_i = a_i - (p + R b_i) so that u_i = l_i / |l_i| points from
the effector to the outlet, the direction the cable pulls.

References
----------
Rivera, Garrido, Riveiro, Silva: "Environment for the Design and Automation
of New CDPR Architectures" (the seed paper): eq. (1)-(3) inverse kinematics,
(4)-(5) closed-form forward kinematics of the planar 2-cable robot,
(6)-(9) statics A T = B.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from cdpr_design.errors import InputError
from cdpr_design.model.design import Design
from cdpr_design.model.limits import lengths_problem
from cdpr_design.statics.pulley import has_pulleys


def rotation_matrix(rx: float = 0.0, ry: float = 0.0, rz: float = 0.0) -> np.ndarray:
    """R = Rx(rx) Ry(ry) Rz(rz) (xyz Euler angles [rad])."""
    cx, sx, cy, sy, cz, sz = np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry), np.cos(rz), np.sin(rz)
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rx @ Ry @ Rz


def pose_rotation(design: Design, pose) -> np.ndarray:
    """The rotation matrix of a pose (identity for 2T and 3T)."""
    full = design.full_pose(pose)
    return rotation_matrix(*full[3:])


def pose_at(design: Design, position3, ori3) -> np.ndarray:
    """The motion's pose coordinates of a full position (3,) [m] and orientation (3,) [rad]."""
    full = np.concatenate([np.asarray(position3, float), np.asarray(ori3, float)])
    return full[list(design.motion.pose_index)]


@dataclass(frozen=True)
class CableGeometry:
    """Cable geometry at one pose (all frame coordinates).

    Attributes
    ----------
    vectors : (m, 3) array
        l_i = a_i - (p + R b_i) [m].
    lengths : (m,) array
        |l_i| [m].
    directions : (m, 3) array
        u_i = l_i / |l_i| (NaN for a zero-length cable).
    attachments : (m, 3) array
        R b_i, the attachment points relative to the platform origin [m].
    anchors : (m, 3) array
        p + R b_i, the attachment points in the frame [m].
    exits : (m, 3) array or None
        Where each free cable really leaves the frame [m]: the swivel-pulley
        tangent point C_i (:mod:`cdpr_design.statics.pulley`), a_i for a point outlet.
    wrap : (m,) array or None
        Wrap angle on the pulley [rad] (0 for a point outlet).

    With a swivel pulley, ``vectors`` is the free segment C_i - (p + R b_i),
    ``lengths`` the total length r beta + |free segment| the winch sees and
    ``directions`` the free segment's unit vector.
    """

    vectors: np.ndarray
    lengths: np.ndarray
    directions: np.ndarray
    attachments: np.ndarray
    anchors: np.ndarray
    exits: np.ndarray | None = None
    wrap: np.ndarray | None = None


def outlet_points(design: Design, anchors: np.ndarray):
    """True outlet points, total lengths and wrap angles for attachment points.

    ``anchors`` is (k, m, 3) (or (m, 3)) attachment points in the frame [m].
    Returns (exits (k, m, 3), lengths (k, m), wrap (k, m)); cables without a
    pulley leave at a_i with length |a_i - anchor|.
    """
    from cdpr_design.statics import pulley as pl

    anc = np.asarray(anchors, float)
    squeeze = anc.ndim == 2
    anc = anc[None] if squeeze else anc
    A = design.outlets
    exits = np.broadcast_to(A[None], anc.shape).copy()
    L = np.linalg.norm(A[None] - anc, axis=2)
    wrap = np.zeros(L.shape)
    for i, c in enumerate(design.cables):
        if c.pulley is None or c.pulley.radius <= 0:
            continue
        g = pl.outlet_geometry(A[i], c.pulley.axis, c.pulley.radius, anc[:, i, :])
        exits[:, i] = g.exits
        L[:, i] = g.lengths
        wrap[:, i] = g.wrap
    if squeeze:
        return exits[0], L[0], wrap[0]
    return exits, L, wrap


def cable_geometry(design: Design, pose) -> CableGeometry:
    """Inverse kinematics of one pose: vectors, lengths and directions of every cable.

    Point outlets: l_i = a_i - (p + R b_i) (paper eq. 1-3).  Swivel pulleys
    (``cables[i].pulley``): the free segment from the attachment to the
    pulley's tangent point and the total length arc + free segment
    (:mod:`cdpr_design.statics.pulley`).
    """
    full = design.full_pose(pose)
    R = rotation_matrix(*full[3:])
    Rb = design.attachments @ R.T
    anchors = full[:3] + Rb
    if has_pulleys(design):
        exits, L, wrap = outlet_points(design, anchors)
        vec = exits - anchors
        free = np.linalg.norm(vec, axis=1)
    else:
        exits, wrap = design.outlets, np.zeros(design.m)
        vec = design.outlets - anchors
        L = free = np.linalg.norm(vec, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = vec / free[:, None]
    u[~(free > 1e-12)] = np.nan
    return CableGeometry(vec, L, u, Rb, anchors, exits, wrap)


def inverse_kinematics(design: Design, pose) -> np.ndarray:
    """Cable lengths [m] at a pose: L_i = |a_i - p - R b_i| (paper eq. 2-3)."""
    return cable_geometry(design, pose).lengths



def structure_matrix(design: Design, pose) -> np.ndarray:
    """Structure (wrench) matrix W (n x m) at a pose (paper eq. 9).

    Column i is [u_i ; (R b_i) x u_i] restricted to the motion's wrench rows.
    A zero-length cable gives a zero column.
    """
    g = cable_geometry(design, pose)
    u = np.nan_to_num(g.directions)
    full = np.vstack([u.T, np.cross(g.attachments, u).T])
    return full[list(design.motion.wrench_rows), :]


def gravity_wrench(design: Design, pose) -> np.ndarray:
    """Wrench of gravity on the effector, restricted to the motion's rows [N, N m].

    Force m g applied at the centre of mass R c (moment (R c) x m g about the
    platform origin).
    """
    R = pose_rotation(design, pose)
    f = design.effector.mass * np.asarray(design.gravity)
    c = R @ np.asarray(design.effector.center_of_mass)
    full = np.concatenate([f, np.cross(c, f)])
    return full[list(design.motion.wrench_rows)]


def inertial_wrench(design: Design, pose, acceleration, angular_velocity=None,
                    angular_acceleration=None) -> np.ndarray:
    """d'Alembert wrench -(m a_c, I alpha + w x I w) on the effector [N, N m].

    ``acceleration`` is the platform origin's linear acceleration (frame,
    motion's position dims); rotation terms use the inertia about the COM,
    rotated to the frame.  Returned restricted to the motion's rows: the
    wrench the cables must balance is -(gravity + inertial + external).
    """
    d = design.motion.dim
    a = np.zeros(3)
    a[:d] = np.asarray(acceleration, float)[:d]
    R = pose_rotation(design, pose)
    c = R @ np.asarray(design.effector.center_of_mass)
    w = np.zeros(3) if angular_velocity is None else np.asarray(angular_velocity, float)
    al = np.zeros(3) if angular_acceleration is None else np.asarray(angular_acceleration, float)
    m = design.effector.mass
    a_c = a + np.cross(al, c) + np.cross(w, np.cross(w, c))
    I = R @ design.effector.inertia_matrix @ R.T
    f = -m * a_c
    tau_c = -(I @ al + np.cross(w, I @ w))
    full = np.concatenate([f, tau_c + np.cross(c, f)])
    return full[list(design.motion.wrench_rows)]


def mass_matrix(design: Design, orientation) -> np.ndarray:
    """The effector's mass matrix at rest M (n, ncoords) at a full orientation (3,) [rad].

    An effector at rest with acceleration a (the motion's coordinates: the reference point's
    linear acceleration [m/s^2], then the second derivatives of the rotation coordinates
    [rad/s^2]) needs the cables to supply M a [N, N m] besides balancing gravity and the
    external wrench: W t + w_gravity + w_external = M a.  The columns are the opposite of
    :func:`inertial_wrench` for each unit acceleration; at rest the angular acceleration is
    E(angles) theta'' (:func:`euler_rates_to_omega`: the term E' theta' vanishes with the
    velocity, as do the Coriolis and gyroscopic terms w x I w).
    """
    mot = design.motion
    ori = np.asarray(orientation, float)
    pose = pose_at(design, np.zeros(3), ori)
    M = np.empty((design.n, len(mot.coords)))
    for k, idx in enumerate(mot.pose_index):
        e = np.zeros(3)
        e[idx % 3] = 1.0
        if idx < 3:
            M[:, k] = -inertial_wrench(design, pose, e)
        else:
            M[:, k] = -inertial_wrench(design, pose, np.zeros(3), angular_acceleration=euler_rates_to_omega(ori, e))
    return M


def required_wrench(design: Design, pose, external=None) -> np.ndarray:
    """w_req = -(w_gravity + w_external): what the cables must supply, W t = w_req."""
    w = gravity_wrench(design, pose)
    if external is not None:
        w = w + np.asarray(external, dtype=float)
    return -w



def euler_rates_to_omega(angles, rates) -> np.ndarray:
    """Angular velocity (frame) [rad/s] of R = Rx(a) Ry(b) Rz(c) for angle rates (3,) [rad/s]."""
    return euler_motion(np.asarray(angles, float)[None], np.asarray(rates, float)[None])[0][0]


def euler_motion(angles, rates, accels=None) -> tuple[np.ndarray, np.ndarray]:
    """Angular velocity w [rad/s] and acceleration alpha [rad/s^2] (k, 3), in the frame, of
    R = Rx(a) Ry(b) Rz(c) moving with xyz Euler angles ``angles`` (k, 3) [rad], their rates
    ``rates`` (k, 3) [rad/s] and second derivatives ``accels`` (k, 3) [rad/s^2] (default 0).

    w = E theta' with the columns of E the axes of the three turns, e_x, Rx(a) e_y and
    Rx(a) Ry(b) e_z; alpha = E theta'' + E' theta' (exact: E' from a' and b')."""
    ang = np.atleast_2d(np.asarray(angles, float))
    rt = np.atleast_2d(np.asarray(rates, float))
    a, b = ang[:, 0], ang[:, 1]
    da, db, dc = rt[:, 0], rt[:, 1], rt[:, 2]
    ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    zero, one = np.zeros_like(a), np.ones_like(a)
    ex = np.stack([one, zero, zero], axis=1)
    ey = np.stack([zero, ca, sa], axis=1)
    ez = np.stack([sb, -sa * cb, ca * cb], axis=1)
    w = da[:, None] * ex + db[:, None] * ey + dc[:, None] * ez
    dey = da[:, None] * np.stack([zero, -sa, ca], axis=1)  # d(ey)/dt
    dez = (da[:, None] * np.stack([zero, -ca * cb, -sa * cb], axis=1)
           + db[:, None] * np.stack([cb, sa * sb, -ca * sb], axis=1))  # d(ez)/dt
    al = db[:, None] * dey + dc[:, None] * dez
    if accels is not None:
        acc = np.atleast_2d(np.asarray(accels, float))
        al = al + acc[:, 0:1] * ex + acc[:, 1:2] * ey + acc[:, 2:3] * ez
    return w, al


# ----------------------------------------------------------------------------
# Forward kinematics
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class FKResult:
    """Forward kinematics result: pose (motion coords) and the length residual [m]."""

    pose: np.ndarray
    residual: float
    method: str


def planar2_closed_form(design: Design, lengths) -> np.ndarray | None:
    """The paper's closed form (eq. 4-5) generalised to any two planar outlets.

    Each attachment point lies on a circle of radius L_i about its outlet; the
    platform origin is the intersection of the circles about a_i - b_i, taking
    the solution below the line joining them (a suspended robot hangs under
    its outlets).  With the paper's geometry (outlets at the same height,
    attachments at (-Bx/2, By/2), (Bx/2, By/2)) this reduces to eq. (4)-(5).
    Returns None when the circles do not meet.
    """
    L1, L2 = float(lengths[0]), float(lengths[1])
    c1 = np.asarray(design.outlets[0, :2]) - design.attachments[0, :2]
    c2 = np.asarray(design.outlets[1, :2]) - design.attachments[1, :2]
    d_vec = c2 - c1
    d = float(np.hypot(*d_vec))
    if d == 0.0 or d > L1 + L2 + 1e-12 or d < abs(L1 - L2) - 1e-12:
        return None
    # distance from c1 along the line to the chord (eq. 4 in the paper's frame)
    a = (L1 * L1 - L2 * L2 + d * d) / (2 * d)
    h = np.sqrt(max(L1 * L1 - a * a, 0.0))
    e = d_vec / d
    nrm = np.array([e[1], -e[0]])  # the side "below" for c1 left of c2
    if nrm[1] > 0:
        nrm = -nrm
    p = c1 + a * e + h * nrm
    return p


def forward_difference_jacobian(fun):
    """The Jacobian ``jac(x, *args)`` of ``fun(x, *args)`` by forward differences, with the step
    sqrt(eps) max(1, |x_j|) [units of x_j] (scipy's own '2-point' step), for scipy's ``least_squares``.

    Given explicitly so that every scipy version solves alike: without it, ``method="lm"`` of
    scipy 1.11 lets MINPACK's lmdif difference with the step sqrt(eps) |x_j|, which for a
    coordinate iterating towards 0 (a rotation at the nominal orientation) is swamped by rounding:
    the Jacobian's column is noise and the solve stalls far above its tolerance.
    """
    from scipy.optimize import approx_fprime

    def jac(x, *args):
        step = np.sqrt(np.finfo(float).eps) * np.maximum(1.0, np.abs(x))
        return np.atleast_2d(approx_fprime(np.asarray(x, float), fun, step, *args))

    return jac


def forward_kinematics(design: Design, lengths, guess=None, tol: float = 1e-12) -> FKResult:
    """The pose for given cable lengths.

    Closed form for a 2T design with two cables (paper eq. 4-5); otherwise a
    Levenberg-Marquardt solve of the length residuals |a_i - p - R b_i| - L_i
    from ``guess`` (default: the centre of the workspace grid at the fixed
    orientation).  With swivel pulleys the residuals use the pulley-aware
    lengths (arc + free segment), so FK inverts :func:`inverse_kinematics`.  Under-constrained robots (m < n) have a family of poses:
    the one found depends on the guess.  ``residual`` is the 2-norm of the
    length residuals [m].
    """
    lengths = np.asarray(lengths, dtype=float).reshape(-1)
    if lengths.size != design.m:
        raise ValueError(f"expected {design.m} cable lengths, got {lengths.size}")
    why = lengths_problem(lengths)
    if why:
        raise InputError(why)
    mot = design.motion
    if mot.name == "2T" and design.m == 2:
        p = planar2_closed_form(design, lengths)
        if p is not None and not has_pulleys(design):
            res = float(np.linalg.norm(inverse_kinematics(design, p) - lengths))
            return FKResult(np.asarray(p, float), res, "closed-form")
        if p is not None and guess is None:
            guess = p  # the point-outlet solution starts the pulley-aware solve
    if guess is None:
        grid = design.workspace.grid
        centre = [(lo + hi) / 2 for lo, hi in zip(grid.lower, grid.upper)]
        ori = list(design.workspace.orientation)
        guess = np.array(centre + ori, dtype=float)
    guess = np.asarray(guess, dtype=float)

    from scipy.optimize import least_squares  # imported here: scipy is slow to import

    def fun(x):
        return inverse_kinematics(design, x) - lengths

    sol = least_squares(fun, guess, jac=forward_difference_jacobian(fun),
                        method="lm" if design.m >= len(guess) else "trf",
                        xtol=tol, ftol=tol, gtol=tol, max_nfev=2000)
    res = float(np.linalg.norm(fun(sol.x)))
    return FKResult(sol.x, res, "levenberg-marquardt" if design.m >= len(guess) else "trust-region")
