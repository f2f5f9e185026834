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

import functools
import itertools
import math
from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import jitable, njit, njit_inline
from cdpr_design.kernels.hsm import basis_factor, facet_norm2, null_vector, slot_dot
from cdpr_design.kernels.linalg import RANK_TOL, gram_of_inverse, orthogonalize_column
from cdpr_design.kernels.parallel import run_blocks


@njit
def facet_normal(W, subset, Q, c):
    """Unit normal ``c`` (n,) of the hyperplane spanned by the columns ``subset`` (n-1,) of ``W``
    (n, m), by Gram-Schmidt (twice) in ``Q`` (n, n) work; returns False when those columns have
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
        norm = orthogonalize_column(Q, j, n)
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
    for i in range(n):  # orthogonalised in Q's last column
        Q[i, k1] = 1.0 if i == best_r else 0.0
    norm = orthogonalize_column(Q, k1, n)
    for i in range(n):
        c[i] = Q[i, k1] / norm
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
    Q = np.empty((n, n))
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


#: Relative gap [-] below which an axis' least acceleration above its greatest is a single point
#: reached both ways (rounding), not an empty range.
TOUCH_TOL = 1e-9


@njit
def close_axes(axes, empty):
    """The axis ranges ``axes`` (d, 2) [m/s^2] made final: NaN both where none is reachable (``empty``,
    or the least above the greatest by more than :data:`TOUCH_TOL` of their size); a range whose
    ends crossed by less is the one point between them (the axis touches the polytope at a vertex,
    as it does at a pose where only gravity is left)."""
    for k in range(axes.shape[0]):
        lo, hi = axes[k, 0], axes[k, 1]
        if empty or lo > hi + TOUCH_TOL * max(1.0, max(abs(lo), abs(hi))):
            axes[k, 0] = np.nan
            axes[k, 1] = np.nan
        elif lo > hi:
            axes[k, 0] = 0.5 * (lo + hi)
            axes[k, 1] = axes[k, 0]


@njit_inline
def box_support(c, elo, ehi):
    """(up, down): the largest and least -c . w_e [N] over the external wrench box ``elo`` ..
    ``ehi`` (n,) for the normal ``c`` (n,) (the box's support function, no vertex enumerated)."""
    up = 0.0
    down = 0.0
    for i in range(c.shape[0]):
        up += max(-c[i] * elo[i], -c[i] * ehi[i])
        down += min(-c[i] * elo[i], -c[i] * ehi[i])
    return up, down


@njit_inline
def facet_sides(bp, bm, cw, up, down, h, hn, tol, axes, worst, radius, held, empty):
    """One facet's two half-spaces of the accelerations, (M_t^T c) . a <= s, folded into the pose's
    figures: its bounds ``bp``, ``bm`` on c . W t, ``cw`` = c . w_nom, the box's ``up`` and ``down``
    (:func:`box_support`), ``h`` (d,) = M_t^T c of norm ``hn`` (a facet with |h| or a component at
    or below ``tol`` bounds nothing that way: only its slack's sign counts), all for one scale of
    c; lowers ``radius`` (its direction into ``worst``) and narrows ``axes`` (d, 2).  Returns
    (radius, held, empty)."""
    d = h.shape[0]
    for side in range(2):
        sign = 1.0 if side == 0 else -1.0
        slack = (bp - cw - up) if side == 0 else (cw + down - bm)
        if slack < 0.0:
            held = False
        if hn > tol:
            if slack / hn < radius:
                radius = slack / hn
                for k in range(d):
                    worst[k] = sign * h[k] / hn
        elif slack < 0.0:
            empty = True
        for k in range(d):
            hk = sign * h[k]
            if abs(hk) > tol:
                if hk > 0.0:
                    axes[k, 1] = min(axes[k, 1], slack / hk)
                else:
                    axes[k, 0] = max(axes[k, 0], slack / hk)
            elif slack < 0.0:
                axes[k, 0] = np.nan
                axes[k, 1] = np.nan
    return radius, held, empty


@njit
def pose_capability(W, lo, hi, wnom, elo, ehi, Mt, combos, Q, c, axes, worst):
    """The acceleration capability at one pose; returns the radius [m/s^2].

    ``W`` (n, m) structure matrix, ``lo``, ``hi`` (m,) tension bounds [N], ``wnom`` (n,) the
    wrench the cables supply at rest without external load (-w_g) [N, N m], ``elo``, ``ehi`` (n,)
    the external wrench box [N, N m] (zeros: none), ``Mt`` (n, d) the mass matrix's translational
    columns [kg, kg m], ``combos`` the (C(m, n-1), n-1) cable subsets, ``Q`` (n, n) and ``c``
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
        for i in range(n):
            cw += c[i] * wnom[i]
        up, down = box_support(c, elo, ehi)
        hn = 0.0
        for k in range(d):
            s = 0.0
            for i in range(n):
                s += Mt[i, k] * c[i]
            h[k] = s
            hn += s * s
        radius, held, empty = facet_sides(bp, bm, cw, up, down, h, math.sqrt(hn), 1e-12 * mscale, axes, worst,
                                          radius, held, empty)
    if facets == 0:
        for k in range(d):
            axes[k, 0] = np.nan
            axes[k, 1] = np.nan
            worst[k] = np.nan
        return np.nan
    close_axes(axes, empty)
    if not held:
        return 0.0
    return radius


#: The work arrays of :func:`pose_capability_factored` for n wrench rows, m cables and d
#: translational axes (:func:`make_work`): the tableau ``tab`` (n, m + n) = [G W | G], G = W_B^-1
#: (:func:`~cdpr_design.kernels.hsm.basis_factor`), its ``slot`` (m,), ``nbc`` (max(m - n, 1),) and
#: ``bcol`` (n,) int64, ``M`` = G G^T (n, n), ``Gw`` = G w_nom (n,), ``GM`` = G M_t (n, d), the
#: null-vector system ``A`` and ``minor`` (n, n) and ``mu`` (n + 1,), ``h`` (d,), and ``Q``
#: (n, n), ``c`` (n,) of :func:`pose_capability` (``c`` also a facet's normal G^T mu).
Work = namedtuple("Work", "tab slot nbc bcol M Gw GM A minor mu h Q c")
#: The facets of the factored W as positions, the same for every pose (:func:`facet_slots`): facet f
#: holds ``k[f]`` non-basic columns, at positions ``K[f, :k[f]]`` of the non-basic list, and frees
#: the basis slots ``F[f, :k[f] + 1]``; (C(m, n - 1),) and (C(m, n - 1), max(m - n, 1) or n) int64.
Slots = namedtuple("Slots", "k K F")


@functools.cache
def facet_slots(n: int, m: int) -> Slots:
    """The :class:`Slots` of n wrench rows and m >= n cables: every subset of n - 1 columns of
    W P = W_B [I F] is k <= min(m - n, n - 1) non-basic columns and the basis columns outside k + 1
    free slots (hyperplane shifting's enumeration, :func:`~cdpr_design.kernels.hsm.hsm_enumerate`)."""
    r = m - n
    rows = [(k, K, F) for k in range(min(r, n - 1) + 1) for K in itertools.combinations(range(r), k)
            for F in itertools.combinations(range(n), k + 1)]
    kk = np.array([k for k, _, _ in rows], dtype=np.int64)
    Ks = np.zeros((len(rows), max(r, 1)), dtype=np.int64)
    Fs = np.zeros((len(rows), n), dtype=np.int64)
    for f, (k, K, F) in enumerate(rows):
        Ks[f, :k] = K
        Fs[f, :k + 1] = F
    return Slots(kk, Ks, Fs)


@jitable
def make_work(n, m, d):
    """The :class:`Work` arrays of one thread (allocate once per block of poses)."""
    r = max(m - n, 1)
    return Work(np.empty((n, m + n)), np.empty(m, dtype=np.int64), np.empty(r, dtype=np.int64),
                np.empty(n, dtype=np.int64), np.empty((n, n)), np.empty(n), np.empty((n, d)), np.empty((n, n)),
                np.empty((n, n)), np.empty(n + 1), np.empty(d), np.empty((n, n)), np.empty(n))


@njit
def pose_capability_factored(W, lo, hi, wnom, elo, ehi, Mt, combos, slots, axes, worst, S):
    """:func:`pose_capability` (same arguments, results and conventions) with the facet normals of
    the basis factorisation W P = W_B [I F] instead of a Gram-Schmidt per facet: every subset of
    n - 1 columns is a set K of k non-basic columns and the basis columns outside k + 1 free slots
    Fr (``slots``, :func:`facet_slots`), its normal nu = G^T mu with mu (on Fr) the null vector of
    F's rows Fr on K.  Then c . W_j = mu . (G W)_j (mu_f on the free slots' basis columns, zero on
    the subset's), c . w_nom = mu . G w_nom, M_t^T c = (G M_t)^T mu, each up to the common factor
    1 / |nu|, |nu|^2 = mu^T (G G^T) mu, which every slack / |M_t^T c| and axis bound leaves out.
    ``S`` the thread's :class:`Work`.  A pose whose W is not finite or has rank < n (no basis) is
    :func:`pose_capability`'s."""
    n, m = W.shape
    d = Mt.shape[1]
    finite = True
    for i in range(n):
        for j in range(m):
            if not math.isfinite(W[i, j]):
                finite = False
    if not finite or m < n or not basis_factor(W, S.tab, S.slot, S.nbc, S.bcol):
        return pose_capability(W, lo, hi, wnom, elo, ehi, Mt, combos, S.Q, S.c, axes, worst)
    tab, M, Gw, GM, A, minor, mu, h, nu = S.tab, S.M, S.Gw, S.GM, S.A, S.minor, S.mu, S.h, S.c
    nbc, bcol = S.nbc, S.bcol
    r = m - n
    gram_of_inverse(tab, n, m, M)
    mscale = 0.0
    box = False
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += tab[i, m + j] * wnom[j]
        Gw[i] = s
        for k in range(d):
            s = 0.0
            for j in range(n):
                s += tab[i, m + j] * Mt[j, k]
            GM[i, k] = s
            mscale = max(mscale, abs(Mt[i, k]))
        if elo[i] != 0.0 or ehi[i] != 0.0:
            box = True
    for k in range(d):
        axes[k, 0] = -np.inf
        axes[k, 1] = np.inf
        worst[k] = np.nan
    radius = np.inf
    held = True
    empty = False
    for f in range(slots.k.shape[0]):
        kk = slots.k[f]
        Kc, Fr = slots.K[f], slots.F[f]
        nf = kk + 1
        for e in range(kk):
            col = nbc[Kc[e]]
            for g in range(nf):
                A[e, g] = tab[Fr[g], col]
        if not null_vector(A, kk, mu, minor):
            continue
        nrm2 = facet_norm2(mu, M, Fr, nf)
        if not nrm2 > 0.0:
            continue
        bp = 0.0
        bm = 0.0
        for g in range(nf):  # the free slots' basis columns: l = mu_g
            j = bcol[Fr[g]]
            bp += max(mu[g] * lo[j], mu[g] * hi[j])
            bm += min(mu[g] * lo[j], mu[g] * hi[j])
        e = 0
        for q in range(r):  # the non-basic columns outside K (K is sorted)
            if e < kk and Kc[e] == q:
                e += 1
                continue
            j = nbc[q]
            lj = slot_dot(mu, tab, Fr, nf, j)
            bp += max(lj * lo[j], lj * hi[j])
            bm += min(lj * lo[j], lj * hi[j])
        cw = 0.0
        for g in range(nf):
            cw += mu[g] * Gw[Fr[g]]
        up = 0.0
        down = 0.0
        if box:
            for i in range(n):
                nu[i] = slot_dot(mu, tab, Fr, nf, m + i)
            up, down = box_support(nu, elo, ehi)
        hn = 0.0
        for k in range(d):
            s = slot_dot(mu, GM, Fr, nf, k)
            h[k] = s
            hn += s * s
        # pose_capability's tolerance, for a normal of length |nu|
        radius, held, empty = facet_sides(bp, bm, cw, up, down, h, math.sqrt(hn), 1e-12 * mscale * math.sqrt(nrm2),
                                          axes, worst, radius, held, empty)
    close_axes(axes, empty)
    if not held:
        return 0.0
    return radius


@njit
def _capability_loop(k0, k1, W, lo, hi, wnom, elo, ehi, Mt, combos, slots, radius, axes, worst, S):
    for p in range(k0, k1):
        radius[p] = pose_capability_factored(W[p], lo[p], hi, wnom, elo, ehi, Mt, combos, slots, axes[p], worst[p],
                                             S)


def _capability_block(k0, k1, W, *args):
    """Rows k0..k1-1 of :func:`capability_many`: the block's work arrays, then the compiled loop."""
    n, m = W.shape[1], W.shape[2]
    _capability_loop(k0, k1, W, *args, make_work(n, m, args[5].shape[1]))


def capability_many(W, lo, hi, wnom, elo, ehi, Mt, combos, radius, axes, worst):
    """:func:`pose_capability_factored` at k poses, in blocks on threads
    (:func:`~cdpr_design.kernels.parallel.run_blocks`): ``W`` (k, n, m), ``lo`` (k, m) each pose's
    lower tension bounds [N], the rest as there; fills ``radius`` (k,) [m/s^2], ``axes`` (k, d, 2)
    [m/s^2] and ``worst`` (k, d)."""
    n, m = W.shape[1], W.shape[2]
    slots = facet_slots(n, m) if m >= n else Slots(np.zeros(0, dtype=np.int64), np.zeros((0, 1), dtype=np.int64),
                                                   np.zeros((0, 1), dtype=np.int64))  # no basis: not read
    run_blocks(_capability_block, radius.shape[0], W, lo, hi, wnom, elo, ehi, Mt, combos, slots, radius, axes,
               worst)
