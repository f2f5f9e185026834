"""Batched damped Newton's method on the balance of a hanging effector.

Force and moment balance of an effector on taut cables at many (position,
rotation) pairs (:class:`Balance`), and Newton's method on it from starting
orientations, batched over the pairs (:func:`newton_many`): the unknowns are
the rotation (R = exp([w]) R_0) and the tensions.  Where the unknowns
outnumber the equations (a spatial body on four or more taut cables: a family
of balanced orientations) each step is the minimum-norm step plus a pull along
the family towards w = 0.  Used by :mod:`cdpr_design.statics.hanging.at_positions`
and :mod:`cdpr_design.statics.hanging.family`.

Units: SI (m, N, rad); conventions of :mod:`cdpr_design.statics.hanging.geometry`.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.statics.hanging import geometry as hg


def _cross(a, b):
    """a x b over the last axis (broadcast), without np.cross's overhead."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


class Balance:
    """Force and moment balance at many (position, rotation) pairs, scaled: forces by the
    weight, moments by the weight times the effector's length scale."""

    def __init__(self, geo: hg.Geometry, planar: bool):
        self.geo = geo
        self.rows = [0, 1, 5] if planar else list(range(6))
        self.rot = [2] if planar else [0, 1, 2]
        sc = np.array([1.0, 1.0, 1.0, geo.size, geo.size, geo.size]) * geo.weight
        self.scale = sc[self.rows]

    def wrenches(self, P, R):
        """At N configurations (P (N, 3) [m], R (N, 3, 3)): the cables' unit wrenches W (N, 6, m)
        [1, m], the weight's and external force's wrench (N, 6) [N, N m], and the cables' R b (N, m, 3) [m], lengths
        L (N, m) [m] and directions u (N, m, 3)."""
        geo = self.geo
        Rb, _, L, u = geo.cables_many(P, R)
        W = np.concatenate([u, _cross(Rb, u)], axis=2).transpose(0, 2, 1)
        return W, geo.loads_many(R), Rb, L, u

    def residual(self, P, R, t):
        W, wg, *_ = self.wrenches(P, R)
        F = np.einsum("nrm,nm->nr", W, t) + wg
        return F[:, self.rows] / self.scale

    def jacobian(self, P, R, t, w):
        """d(scaled residual)/d(rotation coordinates, tensions / weight) (N, r, nr + m)."""
        geo = self.geo
        W, _, Rb, L, u = self.wrenches(P, R)
        Jw = geo.balance_jacobian_many(P, R, t, (Rb, None, L, u))[:, :, 3:] @ hg.left_jacobian(w)
        J = np.concatenate([Jw[:, :, self.rot], W * geo.weight], axis=2)[:, self.rows]
        return J / self.scale[:, None]


def solve_sym(G, b):
    """G x = b for symmetric positive semi-definite stacks, with a tiny ridge (never singular)."""
    n = G.shape[-1]
    ridge = 1e-14 * (np.trace(G, axis1=-2, axis2=-1)[..., None, None] / n + 1e-300)
    return np.linalg.solve(G + ridge * np.eye(n), b[..., None])[..., 0]


def _step(J, F, w, nr):
    """Newton step (N, nr + m): Gauss-Newton where the rows outnumber the unknowns, else the
    minimum-norm step plus, near balance, a pull along the family towards w = 0."""
    N, r, c = J.shape
    JT = J.transpose(0, 2, 1)
    if c <= r:
        return -solve_sym(JT @ J, np.einsum("nrc,nr->nc", J, F))
    G = J @ JT
    dz = -np.einsum("ncr,nr->nc", JT, solve_sym(G, F))
    v = np.zeros((N, c))
    v[:, :nr] = w
    pull = v - np.einsum("ncr,nr->nc", JT, solve_sym(G, np.einsum("nrc,nc->nr", J, v)))
    size = np.linalg.norm(pull, axis=1, keepdims=True)
    pull = pull * np.minimum(1.0, 0.3 / np.maximum(size, 1e-300))
    near = (np.abs(F).max(axis=1) <= 1e-8)[:, None]
    return dz - np.where(near, pull, 0.0)


def newton_many(geo: hg.Geometry, P, planar: bool, R0, starts, iterations: int = 40):
    """Balanced orientations from each start: (R (k, S, 3, 3), t (k, S, m) [N], balanced (k, S)).

    ``P`` (k, 3) positions [m]; ``R0`` the nominal rotation (3, 3), or one per
    position (k, 1, 3, 3); ``starts`` (S, 3) rotation vectors [rad] (frame
    axes) about it.  A pair is balanced when the
    largest force / moment imbalance is at most 1e-8 max(1, weight) [N, N m].
    Each iteration works on the pairs not yet converged; a pair whose step
    the line search cannot accept twice in a row is given up.
    """
    bal = Balance(geo, planar)
    k, S = len(P), len(starts)
    nr = len(bal.rot)
    Pn = np.repeat(np.asarray(P, float), S, axis=0)
    full = np.tile(np.asarray(starts, float), (k, 1))
    base = np.broadcast_to(np.asarray(R0, float), (k, S, 3, 3)).reshape(-1, 3, 3)
    R = hg.rotvec(full) @ base
    W, wg, *_ = bal.wrenches(Pn, R)
    Wr = W[:, bal.rows] / bal.scale[:, None]
    t = -solve_sym(Wr.transpose(0, 2, 1) @ Wr, np.einsum("nrm,nr->nm", Wr, wg[:, bal.rows] / bal.scale))
    t = np.nan_to_num(t) * geo.weight
    F = np.nan_to_num(bal.residual(Pn, R, t), nan=np.inf)
    active = np.ones(len(Pn), bool)
    fails = np.zeros(len(Pn), int)
    for _ in range(iterations):
        idx = np.flatnonzero(active)
        if not idx.size:
            break
        Pa, Ra, ta, wa, Fa = Pn[idx], R[idx], t[idx], full[idx], F[idx]
        merit = np.abs(Fa).max(axis=1)
        dz = _step(np.nan_to_num(bal.jacobian(Pa, Ra, ta, wa)), np.where(np.isfinite(Fa), Fa, 0.0),
                   wa[:, bal.rot], nr)
        near = merit <= 1e-8
        done = (merit <= 1e-14) & (np.abs(dz).max(axis=1) <= 1e-12)
        lam = np.ones(len(idx))
        pending = ~done
        for _ in range(8):
            sub = np.flatnonzero(pending)
            if not sub.size:
                break
            w2 = wa[sub].copy()
            w2[:, bal.rot] += lam[sub, None] * dz[sub, :nr]
            t2 = ta[sub] + lam[sub, None] * dz[sub, nr:] * geo.weight
            R2 = hg.rotvec(w2) @ base[idx[sub]]
            F2 = np.nan_to_num(bal.residual(Pa[sub], R2, t2), nan=np.inf)
            ok = (np.abs(F2).max(axis=1) < merit[sub]) | near[sub]
            g = idx[sub[ok]]
            full[g], t[g], R[g], F[g] = w2[ok], t2[ok], R2[ok], F2[ok]
            pending[sub[ok]] = False
            lam[sub] *= 0.5
        fails[idx] = np.where(pending, fails[idx] + 1, 0)
        active[idx[done]] = False
        active &= fails < 2
    unscaled = np.abs(F * bal.scale).max(axis=1)
    ok = unscaled <= 1e-8 * max(1.0, geo.weight)
    return R.reshape(k, S, 3, 3), t.reshape(k, S, geo.m), ok.reshape(k, S)


def on_cables(geo: hg.Geometry, S) -> hg.Geometry:
    """The effector, with its loads, on the cables S (indices) only (:meth:`Geometry.on_cables`)."""
    return geo.on_cables(S)
