"""The geometry and statics of a hanging effector at one configuration (plain arrays).

The building blocks of :mod:`cdpr_design.statics.hanging`: rotations, the
exact lowest point of an intersection of balls, the effector on its cables
(:class:`Geometry`: cable vectors, force and moment balance with its
Jacobian, the reduced Hessian that judges stability) and the checked
construction of one from a caller's arrays (:func:`checked_geometry`).

Conventions (docs/spec-format.md): outlets A (m, 3) [m], attachments B (m, 3)
in platform coordinates [m], centre of mass c (3,) [m], mass [kg], gravity g
(3,) [m/s^2].  A configuration is the platform origin p (3,) [m] and the
rotation R (3, 3); the cable vector is l_i = a_i - (p + R b_i) and a cable of
length rho_i [m] allows |l_i| <= rho_i.  The potential energy is
U = -m g . (p + R c) [J].  Small rotations act on the left, R <- exp([w]) R,
with w [rad] in frame coordinates.  Degrees of freedom ("dofs") index the
6-vector (dx, dy, dz, wx, wy, wz): (0, 1, 5) for a planar rigid body,
(0, ..., 5) for a spatial one, (0, 1) or (0, 1, 2) for a point mass.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from cdpr_design.errors import InputError
from cdpr_design.model.design import weight_problem

DOFS_PLANAR = (0, 1, 5)
DOFS_SPATIAL = (0, 1, 2, 3, 4, 5)
DOFS_POINT2 = (0, 1)
DOFS_POINT3 = (0, 1, 2)


# ----------------------------------------------------------------------------
# rotations
# ----------------------------------------------------------------------------

def skew(v) -> np.ndarray:
    """[v]_x, the matrix of v x ; for v (..., 3) a stack (..., 3, 3)."""
    v = np.asarray(v, float)
    K = np.zeros(v.shape + (3,))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    return K


def _series(th, small, exact, taylor):
    """exact(th) where th >= small, taylor(th) below (no division by ~0)."""
    safe = np.where(th < small, 1.0, th)
    return np.where(th < small, taylor(th), exact(safe))


def rotvec(w) -> np.ndarray:
    """exp([w]_x): the rotation by |w| [rad] about w (Rodrigues); w (..., 3) -> (..., 3, 3)."""
    w = np.asarray(w, float)
    th = np.linalg.norm(w, axis=-1)[..., None, None]
    K = skew(w)
    a = _series(th, 1e-8, lambda x: np.sin(x) / x, lambda x: 1.0 - x * x / 6.0)
    b = _series(th, 1e-8, lambda x: (1.0 - np.cos(x)) / x ** 2, lambda x: 0.5 + 0.0 * x)
    return np.eye(3) + a * K + b * (K @ K)


def left_jacobian(w) -> np.ndarray:
    """J with exp([w + dw]) = exp([J dw]) exp([w]) to first order; w (..., 3) -> (..., 3, 3)."""
    w = np.asarray(w, float)
    th = np.linalg.norm(w, axis=-1)[..., None, None]
    K = skew(w)
    a = _series(th, 1e-6, lambda x: (1.0 - np.cos(x)) / x ** 2, lambda x: 0.5 + 0.0 * x)
    b = _series(th, 1e-6, lambda x: (x - np.sin(x)) / x ** 3, lambda x: 1.0 / 6.0 + 0.0 * x)
    return np.eye(3) + a * K + b * (K @ K)


def rot_z(phi: float) -> np.ndarray:
    co, si = math.cos(phi), math.sin(phi)
    return np.array([[co, -si, 0.0], [si, co, 0.0], [0.0, 0.0, 1.0]])


def rot_z_many(phi) -> np.ndarray:
    """Rotations (k, 3, 3) about z by angles phi (k,) [rad]."""
    co, si = np.cos(phi), np.sin(phi)
    R = np.zeros(np.shape(phi) + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1], R[..., 2, 2] = co, -si, si, co, 1.0
    return R


def euler_xyz(R) -> np.ndarray:
    """(rx, ry, rz) [rad] with R = Rx(rx) Ry(ry) Rz(rz) (ry in [-pi/2, pi/2]); R (..., 3, 3) -> (..., 3)."""
    R = np.asarray(R, float)
    s02 = np.clip(R[..., 0, 2], -1.0, 1.0)
    lock = np.abs(R[..., 0, 2]) >= 1.0 - 1e-12  # gimbal lock: everything in rx
    rx = np.where(lock, np.arctan2(R[..., 2, 1], R[..., 1, 1]), np.arctan2(-R[..., 1, 2], R[..., 2, 2]))
    rz = np.where(lock, 0.0, np.arctan2(-R[..., 0, 1], R[..., 0, 0]))
    return np.stack([rx, np.arcsin(s02), rz], axis=-1)


def angle_from(R, R0) -> np.ndarray:
    """The angles [rad] of rotations R (..., 3, 3) from R0 (3, 3 or ..., 3, 3): 2 asin(|R -
    R0|_F / sqrt 8), accurate near R0 too (where acos of the trace loses half the digits)."""
    d = np.asarray(R, float) - np.asarray(R0, float)
    chord = np.sqrt(np.einsum("...ij,...ij->...", d, d) / 8.0)
    return 2.0 * np.arcsin(np.minimum(chord, 1.0))


def rotation_angle(R) -> float:
    """The angle [rad] of a rotation matrix."""
    return float(angle_from(R, np.eye(3)))


def align(v, target) -> np.ndarray:
    """The smallest rotation taking direction v onto direction target (3-vectors)."""
    a = np.asarray(v, float) / np.linalg.norm(v)
    b = np.asarray(target, float) / np.linalg.norm(target)
    axis = np.cross(a, b)
    s, co = float(np.linalg.norm(axis)), float(a @ b)
    if s < 1e-15:
        if co > 0:
            return np.eye(3)
        perp = np.cross(a, [1.0, 0, 0]) if abs(a[0]) < 0.9 else np.cross(a, [0, 1.0, 0])
        return rotvec(math.pi * perp / np.linalg.norm(perp))
    return rotvec(axis / s * math.atan2(s, co))


def tilt_many(R, up) -> np.ndarray:
    """Angles [deg] between R up and up for rotations R (..., 3, 3) (atan2 of the sine and
    cosine: accurate near level too, where acos loses half the digits)."""
    up = np.asarray(up, float)
    v = np.einsum("...ij,j->...i", R, up)
    s = np.linalg.norm(np.cross(v, up), axis=-1)
    return np.degrees(np.arctan2(s, v @ up))


#: Weight of the tie-break between equally tilted orientations in :func:`tilt_rank` (deg of
#: rank per deg of rotation from the nominal orientation).
TIE = 1e-7


def tilt_rank(R, up, R0) -> np.ndarray:
    """The order [deg] in which the hanging search prefers orientations R (..., 3, 3): the
    tilt (:func:`tilt_many`) plus :data:`TIE` x the angle [deg] from the nominal rotation
    R0 (3, 3).  Of orientations equally tilted (a level body that could hang at any yaw,
    say) the one nearest R0 comes first; the term reorders orientations only where their
    tilts differ by less than 180 x TIE deg.  The angle (:func:`angle_from`) is accurate
    near R0, so the term outweighs the rounding of the tilt (about 1e-15 deg) from about
    1e-10 rad away."""
    return tilt_many(R, up) + TIE * np.degrees(angle_from(R, R0))


# ----------------------------------------------------------------------------
# the convex inner problem: lowest point of an intersection of balls
# ----------------------------------------------------------------------------

def _pairs(C, rho, down, tol):
    """Stationary points of the height on the intersection of two spheres (per pair)."""
    _, m, d = C.shape
    out = []
    for i, j in itertools.combinations(range(m), 2):
        e = C[:, j] - C[:, i]
        D = np.linalg.norm(e, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            e = e / D[:, None]
            a = (rho[i] ** 2 - rho[j] ** 2 + D ** 2) / (2.0 * D)
            h2 = rho[i] ** 2 - a ** 2
            h = np.sqrt(np.where(h2 >= -2.0 * rho[i] * tol, np.maximum(h2, 0.0), np.nan))
        o = C[:, i] + a[:, None] * e
        if d == 2:
            nrm = np.stack([-e[:, 1], e[:, 0]], axis=1)
            out += [o + h[:, None] * nrm, o - h[:, None] * nrm]
        else:
            w = down[None, :] - (e @ down)[:, None] * e
            wn = np.linalg.norm(w, axis=1)
            flat = ~(wn > 1e-12)  # horizontal circle: every point is as low
            alt = np.cross(e, np.where(np.abs(e[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
            w = np.where(flat[:, None], alt, w)
            with np.errstate(invalid="ignore", divide="ignore"):
                w = w / np.linalg.norm(w, axis=1)[:, None]
            out.append(o + h[:, None] * w)
    return out


def _triples(C, rho, tol):
    """The two points common to three spheres (3-D trilateration), per triple."""
    m = C.shape[1]
    out = []
    for i, j, k in itertools.combinations(range(m), 3):
        with np.errstate(invalid="ignore", divide="ignore"):
            dj = C[:, j] - C[:, i]
            dk = C[:, k] - C[:, i]
            D = np.linalg.norm(dj, axis=1)
            ex = dj / D[:, None]
            ii = np.einsum("nd,nd->n", ex, dk)
            ey = dk - ii[:, None] * ex
            jj = np.linalg.norm(ey, axis=1)
            ey = ey / jj[:, None]
            ez = np.cross(ex, ey)
            x = (rho[i] ** 2 - rho[j] ** 2 + D ** 2) / (2.0 * D)
            y = (rho[i] ** 2 - rho[k] ** 2 + ii ** 2 + jj ** 2) / (2.0 * jj) - ii * x / jj
            z2 = rho[i] ** 2 - x ** 2 - y ** 2
            z = np.sqrt(np.where(z2 >= -2.0 * rho[i] * tol, np.maximum(z2, 0.0), np.nan))
            base = C[:, i] + x[:, None] * ex + y[:, None] * ey
        out += [base + z[:, None] * ez, base - z[:, None] * ez]
    return out


def lowest_points(C, rho, down, tol):
    """The lowest point of every intersection of balls |x - C[n, i]| <= rho_i.

    ``C`` (N, m, d) centres [m] for N problems (d = 2 or 3), ``rho`` (m,)
    radii [m], ``down`` (d,) unit vector along gravity, ``tol`` [m] the
    feasibility tolerance.  Minimising a linear function over an intersection
    of balls is a convex problem whose minimiser lies on at most d spheres
    with non-negative multipliers (KKT; Caratheodory), so it is one of the
    stationary points of the height on the spheres of some subset of at most
    d balls: a ball's lowest point, the lowest point of two spheres'
    intersection (two points in the plane) or a point common to three
    spheres.  Enumerating those candidates and keeping the lowest feasible
    one solves the problem exactly.

    Returns (x (N, d), feasible (N,), violation (N,)): the minimiser (NaN
    where the balls have no common point) and the smallest
    max_i(|x - C_i| - rho_i) over the candidates (<= tol where feasible).
    """
    C = np.asarray(C, float)
    N, m, d = C.shape
    cand = [C[:, i] + rho[i] * down for i in range(m)]
    cand += _pairs(C, rho, down, tol)
    if d == 3:
        cand += _triples(C, rho, tol)
    X = np.stack(cand, axis=1)  # (N, K, d)
    dist = np.linalg.norm(X[:, :, None, :] - C[:, None, :, :], axis=3)
    viol = np.max(dist - rho, axis=2)
    viol = np.where(np.isnan(viol), np.inf, viol)
    feas = viol <= tol
    depth = np.where(feas, X @ down, -np.inf)
    k = np.argmax(depth, axis=1)
    rows = np.arange(N)
    ok = feas[rows, k]
    x = np.where(ok[:, None], X[rows, k], np.nan)
    return x, ok, viol.min(axis=1)


# ----------------------------------------------------------------------------
# statics at one configuration
# ----------------------------------------------------------------------------

class Geometry:
    """One effector and its cables (plain arrays, 3-D form; see the module doc).

    ``force`` (3,) [N]: a constant external force on the effector at its reference point (the
    platform origin), besides its weight (default none).  Its potential -F . p is linear in the
    position and does not depend on the rotation, so it enters the balance and the energy and
    leaves every Hessian as it is.
    """

    def __init__(self, A, B, c, mass, g, force=None):
        self.A = np.ascontiguousarray(A, dtype=float)
        self.B = np.ascontiguousarray(B, dtype=float)
        self.c = np.asarray(c, float).reshape(3)
        self.mass = float(mass)
        self.g = np.asarray(g, float).reshape(3)
        self.force = np.zeros(3) if force is None else np.asarray(force, float).reshape(3)
        self.m = self.A.shape[0]
        self.weight = self.mass * float(np.linalg.norm(self.g))
        size = max(float(np.max(np.linalg.norm(self.B - self.B.mean(0), axis=1), initial=0.0)),
                   float(np.linalg.norm(self.c - self.B.mean(0))), 1e-3)
        self.size = size  # a length scale of the effector [m]

    def energy(self, p, R) -> float:
        """U = -m g . (p + R c) - F . p [J] (F the external :attr:`force`)."""
        return float(-self.mass * self.g @ (p + R @ self.c) - self.force @ p)

    def loads_many(self, R) -> np.ndarray:
        """The wrench (k, 6) [N, N m] of the weight and the external :attr:`force` on the effector
        at rotations ``R`` (k, 3, 3): force m g + F, moment (R c) x m g about the platform origin."""
        R = np.asarray(R, float).reshape(-1, 3, 3)
        f = self.mass * self.g
        out = np.empty((len(R), 6))
        out[:, :3] = f + self.force
        out[:, 3:] = np.cross(R @ self.c, f)
        return out

    def on_cables(self, S) -> Geometry:
        """This effector, with its loads, on the cables ``S`` (indices) only."""
        return Geometry(self.A[list(S)], self.B[list(S)], self.c, self.mass, self.g, self.force)

    def cables(self, p, R):
        """(Rb (m, 3), l (m, 3), L (m,), u (m, 3)) at a configuration."""
        return tuple(x[0] for x in self.cables_many(np.reshape(p, (1, 3)), np.reshape(R, (1, 3, 3))))

    def wrenches(self, p, R):
        """Cable wrenches (6, m) [u_i; R b_i x u_i] and the loads' (6,) [N, N m] (:meth:`loads_many`)."""
        Rb, _, _, u = self.cables(p, R)
        W = np.vstack([u.T, np.cross(Rb, u).T])
        return W, self.loads_many(R)[0]

    def balance(self, p, R, t) -> np.ndarray:
        """W t + w_loads (6,): force [N] and moment about the origin [N m]."""
        W, wg = self.wrenches(p, R)
        return W @ t + wg

    def jacobian(self, p, R, t, S):
        """d(balance)/d(dp, w) (6, 6), d(balance)/dt_S (6, |S|) and d|l_S|/d(dp, w) (|S|, 6)."""
        P1, R1 = np.reshape(p, (1, 3)), np.reshape(R, (1, 3, 3))
        cables = self.cables_many(P1, R1)
        Jz = self.balance_jacobian_many(P1, R1, np.reshape(t, (1, self.m)), cables)[0]
        Rb, u = cables[0][0], cables[3][0]
        Jt = np.vstack([u[S].T, np.cross(Rb[S], u[S]).T])
        G = np.hstack([-u[S], -np.cross(Rb[S], u[S])])
        return Jz, Jt, G

    def balance_jacobian_many(self, P, R, t, cables=None) -> np.ndarray:
        """d(balance)/d(dp, w) at k configurations, the tensions t (k, m) [N] held: (k, 6, 6).

        With S = [R b]_x, P = (I - u u^T) / L and c = R b x u, cable i adds t_i times
        [[-P, P S], [-S P, [u]_x S + S P S]], in closed form ([a]_x [b]_x = b a^T - (a . b) I):
        P S = (S + u c^T) / L, S P = (S - c u^T) / L and [u]_x S + S P S = R b u^T - (u . R b) I
        + (R b (R b)^T - |R b|^2 I + c c^T) / L, summed over the cables with einsum; the weight adds
        [f]_x [R c]_x to the rotation block.  A cable without tension adds nothing (also at length
        0, where its direction is undefined); one pulling at length 0 makes the answer NaN.
        ``cables``: :meth:`cables_many` of (P, R), where the caller has them already.
        """
        P = np.asarray(P, float).reshape(-1, 3)
        R = np.asarray(R, float).reshape(-1, 3, 3)
        t = np.asarray(t, float).reshape(-1, self.m)
        Rb, _, L, u = cables if cables is not None else self.cables_many(P, R)
        pulls = (t != 0.0)[..., None]
        u = np.where(pulls, u, 0.0)
        c = np.cross(Rb, u)
        with np.errstate(invalid="ignore", divide="ignore"):
            tL = np.where(pulls[..., 0], t / L, 0.0)
        outer = lambda w, a, b: np.einsum("km,kmi,kmj->kij", w, a, b)  # noqa: E731
        eye = np.eye(3)
        sRb = skew(np.einsum("km,kmi->ki", tL, Rb))
        J = np.empty((len(P), 6, 6))
        J[:, :3, :3] = outer(tL, u, u) - tL.sum(axis=1)[:, None, None] * eye
        J[:, :3, 3:] = sRb + outer(tL, u, c)
        J[:, 3:, :3] = outer(tL, c, u) - sRb
        diag = np.einsum("km,kmi,kmi->k", t, u, Rb) + np.einsum("km,kmi,kmi->k", tL, Rb, Rb)
        J[:, 3:, 3:] = (outer(t, Rb, u) + outer(tL, Rb, Rb) + outer(tL, c, c) - diag[:, None, None] * eye
                        + skew(self.mass * self.g) @ skew(R @ self.c))
        return J

    def cables_many(self, P, R):
        """:meth:`cables` at k configurations: P (k, 3) [m], R (k, 3, 3) -> (Rb, l (k, m, 3) [m],
        L (k, m) [m], u (k, m, 3); NaN directions where a cable has length 0)."""
        Rb = np.einsum("kij,mj->kmi", R, self.B)
        l = self.A[None] - P[:, None, :] - Rb
        L = np.sqrt(np.einsum("kmi,kmi->km", l, l))
        with np.errstate(invalid="ignore", divide="ignore"):
            u = l / L[..., None]
        return Rb, l, L, u

    def lagrangian_hessian_many(self, P, R, t, cables=None) -> np.ndarray:
        """Hessians (k, 6, 6) of U + sum t_i |l_i| in (dp, w) at k configurations: P (k, 3) [m],
        R (k, 3, 3), t (k, m) [N].

        With S_i = [R b_i]_x, P_i = (I - u_i u_i^T) / L_i and J_i = [-I, S_i] (the
        derivative of l_i), cable i adds t_i (J_i^T P_i J_i + [0, 0; 0, (u_i . R b_i) I -
        (u_i (R b_i)^T + R b_i u_i^T) / 2]); the weight adds m ((g . R c) I - (g (R c)^T +
        R c g^T) / 2) to the rotation block.  ``cables``: :meth:`cables_many` of (P, R), where
        the caller has them already.
        """
        P = np.asarray(P, float).reshape(-1, 3)
        R = np.asarray(R, float).reshape(-1, 3, 3)
        t = np.asarray(t, float).reshape(-1, self.m)
        Rb, _, L, u = cables if cables is not None else self.cables_many(P, R)
        with np.errstate(invalid="ignore", divide="ignore"):
            Pm = (np.eye(3) - u[..., :, None] * u[..., None, :]) / L[..., None, None]
        S = skew(Rb)
        PS = Pm @ S
        sym = 0.5 * (u[..., :, None] * Rb[..., None, :] + Rb[..., :, None] * u[..., None, :])
        dot = np.einsum("kmi,kmi->km", u, Rb)[..., None, None] * np.eye(3)
        w = t[..., None, None]

        def total(block):  # sum over the cables with tension (one of length 0 and none adds no NaN)
            return np.sum(np.where(w != 0.0, w * block, 0.0), axis=1)

        H = np.zeros((len(P), 6, 6))
        H[:, :3, :3] = total(Pm)
        H[:, :3, 3:] = -total(PS)
        H[:, 3:, :3] = total(S @ Pm)
        H[:, 3:, 3:] = total(dot - sym - S @ PS)
        cR = R @ self.c
        g = self.g
        H[:, 3:, 3:] += self.mass * ((cR @ g)[:, None, None] * np.eye(3)
                                     - 0.5 * (g[:, None] * cR[:, None, :] + cR[:, :, None] * g[None, :]))
        return H

    def reduced_hessian_min(self, p, R, t, taut, dofs) -> float:
        """Smallest eigenvalue of the Lagrangian's Hessian on the tangent space of the
        taut cables' length constraints (restricted to ``dofs``); +inf when that
        space is {0} (the taut cables lock the effector).  ``taut``: cable indices."""
        mask = np.zeros((1, self.m), bool)
        mask[0, list(taut)] = True
        return float(self.reduced_hessian_min_many(np.reshape(p, (1, 3)), np.reshape(R, (1, 3, 3)),
                                                   np.reshape(t, (1, self.m)), mask, dofs)[0])

    def reduced_hessian_min_many(self, P, R, t, taut, dofs) -> np.ndarray:
        """:meth:`reduced_hessian_min` at k configurations: P (k, 3) [m], R (k, 3, 3), t (k, m)
        [N], ``taut`` (k, m) bool -> (k,).

        The tangent space is the null space of the taut cables' length gradients
        G_i = (-u_i, -(R b_i) x u_i) restricted to ``dofs`` (right singular vectors past the
        numerical rank, singular values > 1e-10 max(1, the largest)); a slack cable's row is
        zero and changes neither.  The answer does not depend on the basis chosen for it.
        """
        dofs = list(dofs)
        P = np.asarray(P, float).reshape(-1, 3)
        R = np.asarray(R, float).reshape(-1, 3, 3)
        taut = np.asarray(taut, bool).reshape(-1, self.m)
        k, d = len(P), len(dofs)
        cables = self.cables_many(P, R)
        H = self.lagrangian_hessian_many(P, R, t, cables)[:, dofs][:, :, dofs]
        Rb, _, _, u = cables
        G = -np.concatenate([u, np.cross(Rb, u)], axis=2)[:, :, dofs]
        G = np.where(taut[..., None], G, 0.0)
        _, sv, Vt = np.linalg.svd(G)
        rank = np.sum(sv > 1e-10 * np.maximum(1.0, sv[:, :1]), axis=1)
        M = Vt @ H @ Vt.transpose(0, 2, 1)  # H in the singular-vector basis: the tangent space last
        out = np.full(k, np.inf)
        for r in np.unique(rank):
            if r < d:
                rows = np.flatnonzero(rank == r)
                out[rows] = np.linalg.eigvalsh(M[rows, r:, r:])[:, 0]
        return out


def point_mass_rotation(geo: Geometry, planar: bool, nominal=None) -> np.ndarray:
    """The rotation that puts a point mass's centre of mass straight below its attachment
    point (the smallest such rotation; ``nominal`` when they coincide)."""
    down = geo.g / np.linalg.norm(geo.g)
    arm = geo.c - geo.B[0]
    if np.linalg.norm(arm) > 1e-12 * geo.size:
        if planar:
            return rot_z(math.atan2(down[1], down[0]) - math.atan2(arm[1], arm[0]))
        return align(arm, down)
    return np.eye(3) if nominal is None else np.asarray(nominal, float)


# ----------------------------------------------------------------------------
# from a caller's arrays
# ----------------------------------------------------------------------------

def check_weight(mass: float, g) -> None:
    """An :class:`InputError` naming ``effector.mass`` and ``gravity`` unless the effector has a weight
    (:func:`~cdpr_design.model.design.has_weight`; mass [kg], g [m/s^2]): an under-constrained
    effector hangs from its cables under it."""
    why = weight_problem(mass, g)
    if why:
        raise InputError(f"effector.mass, gravity: {why}")


def checked_geometry(A, B, c, mass, g, planar: bool) -> Geometry:
    """The :class:`Geometry` of a caller's arrays: ``A``, ``B`` (m, 2|3) [m] padded to 3-D, ``c``
    [m] and ``g`` [m/s^2] likewise; an :class:`InputError` for mismatched shapes, a weightless
    effector (:func:`check_weight`) or a ``planar`` design off the z = 0 plane."""
    A = np.atleast_2d(np.asarray(A, float))
    B = np.atleast_2d(np.asarray(B, float))
    pad = lambda X: np.hstack([X, np.zeros((X.shape[0], 3 - X.shape[1]))]) if X.shape[1] < 3 else X
    A, B = pad(A), pad(B)
    c = np.concatenate([np.asarray(c, float).ravel(), np.zeros(3)])[:3]
    g = np.concatenate([np.asarray(g, float).ravel(), np.zeros(3)])[:3]
    if A.shape != B.shape or A.shape[0] < 1:
        raise InputError(f"outlets {A.shape} and attachments {B.shape} must both be (m, 3)")
    check_weight(mass, g)
    if planar and (np.any(A[:, 2] != 0) or np.any(B[:, 2] != 0) or c[2] != 0 or g[2] != 0):
        raise InputError("a planar design lives in the z = 0 plane")
    return Geometry(A, B, c, mass, g)


def up_of(geo: Geometry) -> tuple:
    """The frame's unit vertical -g/|g| as a tuple (the results' ``up``)."""
    return tuple(float(v) for v in -geo.g / np.linalg.norm(geo.g))
