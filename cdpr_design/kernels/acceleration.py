"""The translational accelerations an effector at rest can reach, pose by pose.

At rest the effector obeys W t + w_g + w_e = M a (no velocity: no Coriolis or
gyroscopic term), so with the tensions t within [t_lo, t_hi] the reachable
accelerations a (zero angular acceleration) are those whose required wrench
M_t a - w_g - w_e lies in the available wrench set Z = {W t}, for every external
wrench w_e of its box.  Z is a zonotope; its facets are the hyperplanes spanned
by n - 1 of the cables (hyperplane shifting, docs/algorithms.md), each giving a
pair of half-spaces c . w <= b+ and -c . w <= -b-.  A half-space of Z is a
half-space of the accelerations, (M_t^T c) . a <= s with the slack
s = b+ - max over the external box of c . (w_nom - w_e) (in closed form: the box's
support function), so the reachable set is the polytope of those half-spaces,
and its largest ball about a = 0 has radius min s / |M_t^T c| (0 when some
s < 0: the pose cannot even be held at rest).

Arrays in SI units, float64, C-contiguous.
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.kernels._jit import njit

#: Relative tolerance of the rank test of a facet's n - 1 columns.
RANK_TOL = 1e-10


@njit
def facet_normal(W, subset, Q, c):
    """Unit normal ``c`` (n,) of the hyperplane spanned by the columns ``subset`` (n-1,) of ``W``
    (n, m), by Gram-Schmidt (twice) into ``Q`` (n, n-1); returns False when those columns have
    rank < n - 1 (no facet)."""
    n = W.shape[0]
    k1 = n - 1
    for j in range(k1):
        col = subset[j]
        norm0 = 0.0
        for i in range(n):
            Q[i, j] = W[i, col]
            norm0 += W[i, col] * W[i, col]
        norm0 = math.sqrt(norm0)
        if not norm0 > 0.0:
            return False
        for _ in range(2):
            for p in range(j):
                d = 0.0
                for i in range(n):
                    d += Q[i, p] * Q[i, j]
                for i in range(n):
                    Q[i, j] -= d * Q[i, p]
        norm = 0.0
        for i in range(n):
            norm += Q[i, j] * Q[i, j]
        norm = math.sqrt(norm)
        if not norm > RANK_TOL * norm0:
            return False
        for i in range(n):
            Q[i, j] /= norm
    # the unit vector orthogonal to Q's columns: the residual of the axis e_r with the largest one
    best, best_r = -1.0, 0
    for r in range(n):
        s = 1.0
        for j in range(k1):
            s -= Q[r, j] * Q[r, j]
        if s > best:
            best, best_r = s, r
    for i in range(n):
        c[i] = 1.0 if i == best_r else 0.0
    for _ in range(2):
        for j in range(k1):
            d = 0.0
            for i in range(n):
                d += Q[i, j] * c[i]
            for i in range(n):
                c[i] -= d * Q[i, j]
    norm = 0.0
    for i in range(n):
        norm += c[i] * c[i]
    norm = math.sqrt(norm)
    for i in range(n):
        c[i] /= norm
    return True


@njit
def facet_bounds(W, lo, hi, c):
    """(b+, b-): the largest and least c . W t [N] over the tensions lo <= t <= hi (m,) [N] for the
    facet normal ``c`` (n,) of ``W`` (n, m): the two hyperplanes of the available wrench set."""
    n, m = W.shape
    bp = 0.0
    bm = 0.0
    for j in range(m):
        a = 0.0
        for i in range(n):
            a += c[i] * W[i, j]
        bp += max(a * lo[j], a * hi[j])
        bm += min(a * lo[j], a * hi[j])
    return bp, bm


@njit
def facets_many(W, lo, hi, combos, normals, bp, bm):
    """The facets of the available wrench set at k poses: ``W`` (k, n, m), ``lo``, ``hi`` (k, m) [N],
    ``combos`` the (F, n-1) cable subsets; fills ``normals`` (k, F, n) unit normals, ``bp`` and
    ``bm`` (k, F) [N] (:func:`facet_bounds`), and zeros for a subset of rank < n - 1 (no facet) or a
    pose whose W is not finite, so that 0 <= 0 stands for it."""
    k, n, m = W.shape
    Q = np.empty((n, max(n - 1, 1)))
    c = np.empty(n)
    for p in range(k):
        finite = True
        for i in range(n):
            for j in range(m):
                if not math.isfinite(W[p, i, j]):
                    finite = False
        for f in range(combos.shape[0]):
            if finite and facet_normal(W[p], combos[f], Q, c):
                for i in range(n):
                    normals[p, f, i] = c[i]
                bp[p, f], bm[p, f] = facet_bounds(W[p], lo[p], hi[p], c)
            else:
                for i in range(n):
                    normals[p, f, i] = 0.0
                bp[p, f] = 0.0
                bm[p, f] = 0.0


@njit
def pose_capability(W, lo, hi, wnom, elo, ehi, Mt, combos, Q, c, axes, worst):
    """The acceleration capability at one pose; returns the radius [m/s^2].

    ``W`` (n, m) structure matrix, ``lo``, ``hi`` (m,) tension bounds [N], ``wnom`` (n,) the
    wrench the cables supply at rest without external load (-w_g) [N, N m], ``elo``, ``ehi`` (n,)
    the external wrench box [N, N m] (zeros: none), ``Mt`` (n, d) the mass matrix's translational
    columns [kg, kg m], ``combos`` the (C(m, n-1), n-1) cable subsets, ``Q`` (n, n-1) and ``c``
    (n,) work.  Fills ``axes`` (d, 2): the least and greatest acceleration [m/s^2] along each axis
    (-inf / inf where unbounded, NaN both where no acceleration along it is reachable), and
    ``worst`` (d,): the unit direction in which the radius is reached (NaN where unbounded).
    Returns 0 when the pose is not held at rest for every external wrench, inf when nothing
    bounds the accelerations (no mass), NaN when W has no facet (rank < n - 1) or is not finite.
    """
    n, m = W.shape
    d = Mt.shape[1]
    for k in range(d):
        axes[k, 0] = -np.inf
        axes[k, 1] = np.inf
        worst[k] = np.nan
    for i in range(n):
        for j in range(m):
            if not math.isfinite(W[i, j]):
                for k in range(d):
                    axes[k, 0] = np.nan
                    axes[k, 1] = np.nan
                return np.nan
    mscale = 0.0
    for i in range(n):
        for k in range(d):
            mscale = max(mscale, abs(Mt[i, k]))
    radius = np.inf
    held = True
    empty = False
    facets = 0
    h = np.empty(d)
    for f in range(combos.shape[0]):
        if not facet_normal(W, combos[f], Q, c):
            continue
        facets += 1
        bp, bm = facet_bounds(W, lo, hi, c)
        cw = 0.0
        up = 0.0
        down = 0.0
        for i in range(n):
            cw += c[i] * wnom[i]
            up += max(-c[i] * elo[i], -c[i] * ehi[i])
            down += min(-c[i] * elo[i], -c[i] * ehi[i])
        hn = 0.0
        for k in range(d):
            s = 0.0
            for i in range(n):
                s += Mt[i, k] * c[i]
            h[k] = s
            hn += s * s
        hn = math.sqrt(hn)
        for side in range(2):
            sign = 1.0 if side == 0 else -1.0
            slack = (bp - cw - up) if side == 0 else (cw + down - bm)
            if slack < 0.0:
                held = False
            if hn > 1e-12 * mscale:
                if slack / hn < radius:
                    radius = slack / hn
                    for k in range(d):
                        worst[k] = sign * h[k] / hn
            elif slack < 0.0:
                empty = True
            for k in range(d):
                hk = sign * h[k]
                if abs(hk) > 1e-12 * mscale:
                    if hk > 0.0:
                        axes[k, 1] = min(axes[k, 1], slack / hk)
                    else:
                        axes[k, 0] = max(axes[k, 0], slack / hk)
                elif slack < 0.0:
                    axes[k, 0] = np.nan
                    axes[k, 1] = np.nan
    if facets == 0:
        for k in range(d):
            axes[k, 0] = np.nan
            axes[k, 1] = np.nan
            worst[k] = np.nan
        return np.nan
    for k in range(d):
        if empty or axes[k, 0] > axes[k, 1]:
            axes[k, 0] = np.nan
            axes[k, 1] = np.nan
    if not held:
        return 0.0
    return radius


@njit
def capability_many(W, lo, hi, wnom, elo, ehi, Mt, combos, radius, axes, worst):
    """:func:`pose_capability` at k poses: ``W`` (k, n, m), ``lo`` (k, m) each pose's lower tension
    bounds [N], the rest as there; fills ``radius`` (k,) [m/s^2], ``axes`` (k, d, 2) [m/s^2] and
    ``worst`` (k, d)."""
    n = W.shape[1]
    Q = np.empty((n, max(n - 1, 1)))
    c = np.empty(n)
    for p in range(W.shape[0]):
        radius[p] = pose_capability(W[p], lo[p], hi, wnom, elo, ehi, Mt, combos, Q, c, axes[p], worst[p])
