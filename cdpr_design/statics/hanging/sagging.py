"""A hanging effector on sagging cables at a held position: its orientation, tensions and stiffness.

At a commanded position p the winches pay out the unstretched lengths L0 that hold the effector
there (as on elastic cables, :mod:`cdpr_design.statics.hanging.compliance`), but a sagging cable
(Irvine's elastic catenary, docs/cable-models.md) pulls along its tangent at the attachment, not
along its chord, with forces (H, VB) that follow from its span X, height Z and L0
(:func:`cdpr_design.kernels.catenary_inv.catenary_inverse_batch`).  The orientation R balances
the weight with those forces, force and moment:

    sum_i (H_i u_i + VB_i up) + m g = 0,   sum_i (R b_i) x (H_i u_i + VB_i up) + (R c) x m g = 0.

The unknowns are the rotation (about the ideal cables' answer, R = exp([v]) R_ideal) and the
unstretched lengths; :func:`sagging_orientations` solves the balance by Newton's method from the
ideal cables' hanging orientation (:mod:`~cdpr_design.statics.hanging.at_positions`) and their
stretched lengths L / (1 + t / EA).  Where the unknowns outnumber the balance (a spatial body on
four or five cables, whose balanced orientations form a family), each step is the one that keeps
the answer nearest the start: the fixed point y = J^T (J J^T)^-1 (J y - r) of the scaled unknowns
y = (v [rad], EA (L0 - L0_start) / (L0 W)) [-], W the weight, is the member of the family nearest
the ideal answer in that metric (the rotation, and the tension change the length change would
make on a straight cable, per weight).  The ideal answer is the least tilted member of its
family; the sagging one is that member moved by the cables' weight, the tilt to first order in
the cables' weight over the tensions (to second where the ideal one is inside its family).

Stability and stiffness at fixed unstretched lengths: K = -dw/dx from each cable's analytic
tangent stiffness (the stiffness kernel's elastic catenary, :func:`sagging_stiffness`), then the
compliance and figures of :func:`~cdpr_design.statics.hanging.compliance.stiffness_of`.

A position where the ideal cables do not hang, where a catenary has no solution or the Newton
iteration does not converge (balance to 1e-9 of the weight in 200 steps), or where the answer is
not stable, is reported unable to hang (status codes of
:mod:`~cdpr_design.statics.hanging.results`), never with numbers it did not converge to.

Units: SI (m, N, rad).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design.statics.hanging import geometry as hg
from cdpr_design.statics.hanging.compliance import HangingStiffness, stiffness_of
from cdpr_design.statics.hanging.results import NO_BALANCE, OK, UNSTABLE, HangingOrientations

#: Balance tolerance relative to the weight, and the Newton steps allowed (the steps towards the
#: family's member nearest the start converge linearly where it is far: crane4 takes up to about 100).
TOL = 1e-9
MAXIT = 200


@dataclass
class SaggingCables:
    """The cables at k hanging poses: ``unstretched`` L0 (k, m) [m], end forces at the effector
    ``H``, ``VB`` (k, m) [N], ``tensions`` at the effector and ``outlet_tensions`` (k, m) [N],
    ``sag`` (k, m) [m] the largest distance from the chord (NaN rows where it cannot hang)."""

    unstretched: np.ndarray
    H: np.ndarray
    VB: np.ndarray
    tensions: np.ndarray
    outlet_tensions: np.ndarray
    sag: np.ndarray


def _frames(geo: hg.Geometry, P, R, up):
    """Per pose and cable: span X (k, m) [m], height Z (k, m) [m], horizontal unit vector u (k, m, 3)
    from the attachment towards the outlet, and R b (k, m, 3) [m]."""
    Rb = np.einsum("kij,mj->kmi", R, geo.B)
    l = geo.A[None] - P[:, None, :] - Rb
    Z = l @ up
    h = l - Z[..., None] * up
    X = np.linalg.norm(h, axis=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.where(X[..., None] > 1e-14, h / X[..., None], 0.0)
    return X, Z, u, Rb


def _forces(geo, P, R, L0, w, EA, up, guess=None):
    """(H, VB (k, m) [N], ok (k,), F (k, m, 3) [N], Rb) of every cable at poses (P, R) with lengths L0."""
    from cdpr_design.kernels.catenary_inv import CAT_CONVERGED, catenary_inverse_batch

    X, Z, u, Rb = _frames(geo, P, R, up)
    k, m = X.shape
    c = np.ascontiguousarray
    nan = np.full(k * m, np.nan)
    H0, V0 = (nan, nan) if guess is None else (c(guess[0].ravel()), c(guess[1].ravel()))
    H, VB, status, _ = catenary_inverse_batch(c(X.ravel()), c(Z.ravel()), c(L0.ravel()), c(np.tile(w, k)),
                                              c(np.tile(EA, k)), H0, V0, 1e-13, 100)
    H, VB = H.reshape(k, m), VB.reshape(k, m)
    ok = np.all(status.reshape(k, m) == CAT_CONVERGED, axis=1)
    F = H[..., None] * u + VB[..., None] * up
    return H, VB, ok, F, Rb


def _wrench(geo, P, R, L0, w, EA, up, guess=None):
    """The wrench on the effector (k, 6) [N, N m] (moments about the platform origin), the forces
    (H, VB) and whether every catenary was solved."""
    H, VB, ok, F, Rb = _forces(geo, P, R, L0, w, EA, up, guess)
    out = np.concatenate([F.sum(1), np.cross(Rb, F).sum(1)], axis=1) + geo.loads_many(R)
    return out, H, VB, ok


def _rotate(R, v, planar):
    """exp([v]) R for rotation vectors v (k, d) [rad] (d = 1: about z)."""
    w = np.zeros((len(v), 3))
    if planar:
        w[:, 2] = v[:, 0]
    else:
        w[:] = v
    return hg.rotvec(w) @ R


def sagging_orientations(geo: hg.Geometry, P, planar: bool, ideal: HangingOrientations, w, EA):
    """The hanging orientation at positions ``P`` (k, 3) [m] on sagging cables of weight per length
    ``w`` (m,) [N/m] and axial stiffness ``EA`` (m,) [N] (module doc), started from the ideal
    cables' answer ``ideal`` at the same positions: (HangingOrientations, SaggingCables).  The
    orientations' ``hessian_min`` is the stiffness matrix's (no rigid constraints)."""
    P = np.asarray(P, float).reshape(-1, 3)
    k, m = len(P), geo.m
    up = -geo.g / np.linalg.norm(geo.g)
    W = geo.weight
    w = np.asarray(w, float)
    EA = np.asarray(EA, float)
    rows_bal = [0, 1, 5] if planar else list(range(6))
    nv = 1 if planar else 3
    R = ideal.rotation.copy()
    status = ideal.status.copy()
    L0 = np.full((k, m), np.nan)
    Hs, Vs = np.full((k, m), np.nan), np.full((k, m), np.nan)
    todo = np.flatnonzero(status == OK)
    if todo.size:
        R0, Pt = ideal.rotation[todo], P[todo]
        L = np.linalg.norm(geo.A[None] - Pt[:, None, :] - np.einsum("kij,mj->kmi", R0, geo.B), axis=2)
        start = L / (1.0 + np.nan_to_num(ideal.tensions[todo]) / EA)
        scale = start * W / EA  # dL0 per unit of the scaled unknown (module doc)
        n = todo.size
        y = np.zeros((n, nv + m))
        Hg, Vg = np.full((n, m), np.nan), np.full((n, m), np.nan)
        done = np.zeros(n, bool)
        act = np.arange(n)

        def balance(rows, yv, guess):
            """:func:`_wrench` of the rows ``rows`` at the scaled unknowns ``yv``."""
            return _wrench(geo, Pt[rows], _rotate(R0[rows], yv[:, :nv], planar), start[rows] + scale[rows] * yv[:, nv:],
                           w, EA, up, guess)

        for _ in range(MAXIT):  # the rows not yet converged (a row whose catenary has no solution stops)
            if not act.size:
                break
            guess = (Hg[act], Vg[act])
            r, H, VB, ok = balance(act, y[act], guess)
            Hg[act], Vg[act] = H, VB
            r = r[:, rows_bal] / W
            conv = ok & (np.abs(r).max(axis=1) <= TOL)
            done[act[conv]] = True
            keep = ok & ~conv
            act, r, guess = act[keep], r[keep], (H[keep], VB[keep])
            if not act.size:
                break
            ya = y[act]
            J = np.empty((act.size, len(rows_bal), nv + m))
            for j in range(nv + m):  # forward differences of the scaled unknowns
                yj = ya.copy()
                yj[:, j] += 1e-7
                rj, *_ = balance(act, yj, guess)
                J[:, :, j] = (rj[:, rows_bal] / W - r) / 1e-7
            rhs = np.einsum("kij,kj->ki", J, ya) - r
            JJ = J @ J.transpose(0, 2, 1)
            try:
                lam = np.linalg.solve(JJ, rhs[..., None])[..., 0]
            except np.linalg.LinAlgError:  # a singular balance (degenerate): least squares
                lam = np.stack([np.linalg.lstsq(np.nan_to_num(JJ[i]), np.nan_to_num(rhs[i]), rcond=None)[0]
                                for i in range(len(JJ))])
            step = np.einsum("kji,kj->ki", J, lam) - ya
            y[act] = _damped(lambda yt, rows=act, g=guess: balance(rows, yt, g), ya, step, np.abs(r).max(axis=1),
                             np.ones(act.size, bool), W, rows_bal)
        Rk = _rotate(R0, y[:, :nv], planar)
        Lk = start + scale * y[:, nv:]
        good = done & np.isfinite(y).all(axis=1)
        R[todo] = np.where(good[:, None, None], Rk, np.nan)
        L0[todo] = np.where(good[:, None], Lk, np.nan)
        Hs[todo] = np.where(good[:, None], Hg, np.nan)
        Vs[todo] = np.where(good[:, None], Vg, np.nan)
        status[todo[~good]] = NO_BALANCE
    t = np.hypot(Hs, Vs)
    out = HangingOrientations(R, t, status, np.full(k, np.nan), planar, up)
    cables = SaggingCables(L0, Hs, Vs, t, np.hypot(Hs, Vs + w * L0), _sag(geo, P, R, L0, Hs, Vs, w, EA, up))
    return out, cables


def _damped(balance, y, step, res, active, W, rows_bal):
    """y + a step, halved (up to 10 times) where the balance's largest residual does not fall;
    ``balance(yt)`` is the wrench, forces and success at the scaled unknowns ``yt`` (:func:`_wrench`),
    ``W`` the effector's weight [N] the residual is scaled by."""
    alpha = np.where(active, 1.0, 0.0)
    out = y.copy()
    pending = active.copy()
    for _ in range(11):
        if not pending.any():
            break
        yt = y + alpha[:, None] * step
        r, _, _, ok = balance(yt)
        better = ok & (np.abs(r[:, rows_bal] / W).max(axis=1) < res)
        take = pending & (better | (alpha < 2e-3))
        out[take] = yt[take]
        pending &= ~take
        alpha = np.where(pending, 0.5 * alpha, alpha)
    return out


def _sag(geo, P, R, L0, H, VB, w, EA, up):
    """The largest distance of each cable from its chord [m] (NaN where there is no pose)."""
    from cdpr_design.kernels.catenary import catenary_sag

    out = np.full(L0.shape, np.nan)
    for i, j in zip(*np.nonzero(np.isfinite(L0) & np.isfinite(H))):
        out[i, j] = catenary_sag(H[i, j], VB[i, j], L0[i, j], w[j], EA[j])[0]
    return out


def sagging_stiffness(geo: hg.Geometry, P, planar: bool, h: HangingOrientations, cables: SaggingCables, w, EA,
                      dofs, inertia=None) -> HangingStiffness:
    """The stiffness of the hanging poses ``h`` on sagging cables at their unstretched lengths
    (module doc): K = -dw/dx of each pose by the stiffness kernel's analytic elastic catenary
    (:func:`cdpr_design.kernels.stiffness.pose_matrices`: each cable's tangent stiffness, the inverse
    of Irvine's flexibility in its vertical plane, H / X across it, assembled with the geometric and
    weight terms at the pose's rotation), over ``dofs``, then
    :func:`~cdpr_design.statics.hanging.compliance.stiffness_of` (no rigid constraints).  A pose
    whose catenaries do not converge there is not stable (NaN)."""
    from cdpr_design.kernels.stiffness import Arrays, pose_matrices

    P = np.asarray(P, float).reshape(-1, 3)
    k, d = len(P), len(dofs)
    up = -geo.g / np.linalg.norm(geo.g)
    K = np.full((k, d, d), np.nan)
    ok = h.status == OK
    c64 = np.ascontiguousarray
    K6, M6 = np.empty((6, 6)), np.empty((6, 6))
    sel, f = np.arange(6, dtype=np.int64), geo.mass * geo.g
    fixed = dict(A=geo.A, EA=c64(EA, dtype=float), Linv=np.eye(6), sel=sel, d=3, w=c64(w, dtype=float),
                 up=c64(up), M0=np.zeros((6, 6)), lump=np.zeros(geo.m))
    for r in np.flatnonzero(ok):
        R = h.rotation[r]
        ar = Arrays(Rb=c64(geo.B @ R.T), Kg=c64(-hg.skew(f) @ hg.skew(R @ geo.c)), **fixed)
        if pose_matrices(P[r, 0], P[r, 1], P[r, 2], c64(cables.tensions[r]), c64(cables.unstretched[r]), ar, K6, M6):
            K[r] = 0.5 * (K6 + K6.T)[np.ix_(dofs, dofs)]
        else:
            ok[r] = False
    G = np.zeros((k, 0, d))
    return stiffness_of(geo, K, G, ok, dofs, h.rotation, inertia)


def hang_on_sagging_cables(geo, P, planar, ideal, w, EA, dofs, inertia=None):
    """:func:`sagging_orientations` then :func:`sagging_stiffness`; a pose that is not stable is
    reported ``UNSTABLE`` (rotation and tensions NaN): (HangingOrientations, SaggingCables,
    HangingStiffness)."""
    h, cables = sagging_orientations(geo, P, planar, ideal, w, EA)
    s = sagging_stiffness(geo, P, planar, h, cables, w, EA, dofs, inertia)
    bad = (h.status == OK) & ~s.stable
    h.status[bad] = UNSTABLE
    h.rotation[bad] = np.nan
    h.tensions[bad] = np.nan
    for name in ("unstretched", "H", "VB", "tensions", "outlet_tensions", "sag"):
        getattr(cables, name)[bad] = np.nan
    h.hessian_min = np.where(h.status == OK, s.hessian_min, np.nan)
    return h, cables, s
