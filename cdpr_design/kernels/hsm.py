"""Wrench feasibility and capacity margin by hyperplane shifting (HSM).

Closed forms for square systems (m = n) and the basis-factored HSM for any
m != n, with the wrench-closure test from the same facets (Gouttefarde & Krut
2010; Bouchard, Gosselin & Moore 2010; docs/algorithms.md).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import jitable, njit, njit_fast, njit_folded, njit_inline
from cdpr_design.kernels.hsm_small import hsm_one, hsm_two
from cdpr_design.kernels.linalg import CLOSURE_TOL, RANK_TOL, det_in_place, det_small, gram_of_inverse, inverse_into


@njit_inline
def square_work(n):
    """The work arrays of :func:`square_eval_into`: W^-1 (n, n), its row norms (n,) and the
    Gauss-Jordan tableau (n, 2n)."""
    return np.empty((n, n)), np.empty(n), np.empty((n, 2 * n))


@njit_folded
def square_eval_into(W, wreq, tmin, tmax, t, Winv, rn, a):
    """Tensions and capacity margin of a square structure matrix ``W`` (n, n) in the given work
    arrays (allocates nothing): ``Winv`` (n, n), ``rn`` (n,) and ``a`` (n, >= 2n).

    For m = n the tensions are unique, t = W^-1 w, and the capacity margin [N] is
    min_i min(t_i - t_min,i, t_max,i - t_i) / ||row_i(W^-1)||_2, minimised over
    the required-wrench vertices (rows of ``wreq``); ``t`` receives the
    tensions [N] for the first vertex.  Returns (rank_ok, margin).  This equals the
    hyperplane-shifting margin (the facet normals of a parallelotope are the
    rows of W^-1)."""
    n = W.shape[0]
    nv = wreq.shape[0]
    if n == 2:
        det = W[0, 0] * W[1, 1] - W[0, 1] * W[1, 0]
        scale = max(max(abs(W[0, 0]), abs(W[0, 1])), max(abs(W[1, 0]), abs(W[1, 1])))
        if abs(det) <= RANK_TOL * scale * scale:
            for i in range(2):
                t[i] = np.nan
            return False, np.nan
        i00 = W[1, 1] / det
        i01 = -W[0, 1] / det
        i10 = -W[1, 0] / det
        i11 = W[0, 0] / det
        r0 = math.sqrt(i00 * i00 + i01 * i01)
        r1 = math.sqrt(i10 * i10 + i11 * i11)
        margin = np.inf
        for k in range(nv):
            t0 = i00 * wreq[k, 0] + i01 * wreq[k, 1]
            t1 = i10 * wreq[k, 0] + i11 * wreq[k, 1]
            if k == 0:
                t[0] = t0
                t[1] = t1
            s0 = min(t0 - tmin[0], tmax[0] - t0) / r0
            s1 = min(t1 - tmin[1], tmax[1] - t1) / r1
            margin = min(margin, min(s0, s1))
        return True, margin
    if not inverse_into(W, Winv, a):
        for i in range(n):
            t[i] = np.nan
        return False, np.nan
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += Winv[i, j] * Winv[i, j]
        rn[i] = math.sqrt(s)
    margin = np.inf
    for k in range(nv):
        for i in range(n):
            ti = 0.0
            for j in range(n):
                ti += Winv[i, j] * wreq[k, j]
            if k == 0:
                t[i] = ti
            margin = min(margin, min(ti - tmin[i], tmax[i] - ti) / rn[i])
    return True, margin


@njit
def facet_normal(W, subset, nu):
    """Unit normal ``nu`` (n) of the hyperplane spanned by the columns ``subset`` (n-1).

    Generalised cross product: nu_k = (-1)^k det(W_S without row k).
    Returns False when those columns have rank < n-1 (no facet).
    """
    n = W.shape[0]
    k1 = n - 1
    if n == 2:
        c = subset[0]
        nu[0] = -W[1, c]
        nu[1] = W[0, c]
    elif n == 3:
        a = subset[0]
        b = subset[1]
        nu[0] = W[1, a] * W[2, b] - W[2, a] * W[1, b]
        nu[1] = W[2, a] * W[0, b] - W[0, a] * W[2, b]
        nu[2] = W[0, a] * W[1, b] - W[1, a] * W[0, b]
    else:
        M = np.empty((k1, k1))
        sign = 1.0
        for k in range(n):
            r = 0
            for i in range(n):
                if i == k:
                    continue
                for j in range(k1):
                    M[r, j] = W[i, subset[j]]
                r += 1
            nu[k] = sign * det_small(M, k1)
            sign = -sign
    # Hadamard bound: |nu| <= prod of column norms; relative rank test
    bound = 1.0
    for j in range(k1):
        s = 0.0
        for i in range(n):
            s += W[i, subset[j]] * W[i, subset[j]]
        bound *= math.sqrt(s)
    norm = 0.0
    for i in range(n):
        norm += nu[i] * nu[i]
    norm = math.sqrt(norm)
    if bound == 0.0 or norm <= RANK_TOL * bound:
        return False
    for i in range(n):
        nu[i] /= norm
    return True


#: The scratch arrays of a pose (:func:`make_scratch`), by name; the positions are those of the
#: fields (``scr[0]`` is ``scr.tab``).  n DOF, m cables, r = max(m - n, 1), nv required-wrench rows.
Scratch = namedtuple("Scratch", [
    "tab",      # 0 (n, m + n) [G W | G], G = W_B^-1
    "M",        # 1 (n, n) M = G G^T
    "Gw",       # 2 (max(nv, 1), n) G w_v
    "Gt",       # 3 (n,) G W t_mid
    "A",        # 4 (n, n) A (k, k+1)
    "minor",    # 5 (n, n) minor
    "mu",       # 6 (n + 1,) mu
    "ctol",     # 7 (m,) closure tolerance per column
    "N",        # 8 (m, r) orthonormal null basis
    "tp",       # 9 (m,) t_p
    "J",        # 10 (r, r) J
    "RA",       # 11 (r, r) R of the active normals
    "NA",       # 12 (r, r) active normals
    "VA",       # 13 (r, r) Householder vectors
    "z",        # 14 (r,) z
    "d",        # 15 (r,) d
    "dual",     # 16 (r,) dual direction
    "mult",     # 17 (r + 1,) multipliers
    "slot",     # 18 (m,) int64 slot of each column (-1: non-basic)
    "nbc",      # 19 (max(m - n, 1),) int64 non-basic columns
    "bcol",     # 20 (n,) int64 basis column of each slot
    "spare",    # 21 (n,) int64 (spare)
    "free",     # 22 (n,) int64 facet: free slots
    "fnb",      # 23 (n,) int64 facet: non-basic columns of S (positions in nbc)
    "active",   # 24 (2 m + 1,) int64 active constraints
    "tb",       # 25 (m,) t_b (basic solution)
    "l",        # 26 (m,) facet: l_j
    "trange",   # 27 (m,) t_max - t_min
    "ranges",   # 28 (2, m) hsm_small: range and closure tolerance per position
    "minors",   # 29 (n, n) hsm_small: 2 x 2 minors of F
    "half",     # 30 (3, 4) project_two: half-planes (g0, g1, h, bound)
])


@jitable
def make_scratch(n, m, nv):
    """The :class:`Scratch` arrays of :func:`~cdpr_design.kernels.pose.eval_general` for ``n`` DOF,
    ``m`` cables and ``nv`` required-wrench rows (allocate once per block of poses).

    A named tuple so that every array keeps its contiguous type.  A plain function from Python (numpy
    allocates; nothing is compiled), compiled into the kernels that call it
    (:data:`~cdpr_design.kernels._jit.jitable`).
    """
    r = max(m - n, 1)
    return Scratch(np.empty((n, m + n)), np.empty((n, n)), np.empty((max(nv, 1), n)), np.empty(n),
                   np.empty((n, n)), np.empty((n, n)), np.empty(n + 1), np.empty(m), np.empty((m, r)),
                   np.empty(m), np.empty((r, r)), np.empty((r, r)), np.empty((r, r)), np.empty((r, r)),
                   np.empty(r), np.empty(r), np.empty(r), np.empty(r + 1), np.empty(m, dtype=np.int64),
                   np.empty(max(m - n, 1), dtype=np.int64), np.empty(n, dtype=np.int64),
                   np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64),
                   np.empty(2 * m + 1, dtype=np.int64), np.empty(m), np.empty(m), np.empty(m),
                   np.empty((2, m)), np.empty((n, n)), np.empty((3, 4)))


@njit
def basis_factor(W, tab, slot, nbc, bcol):
    """Basis factorisation W P = W_B [I F] by Gauss-Jordan with complete pivoting.

    ``tab`` (n, m + n) receives [G W | G] with G = W_B^-1 (rows in basis-slot
    order): column j of G W is exactly e_slot(j) for a basis column and the
    column of F for a non-basic one.  ``slot[j]`` is the basis slot of column
    j (-1 if non-basic), ``bcol[s]`` the column in slot s, ``nbc`` lists the
    m - n non-basic columns.  Returns False when rank W < n (a relative pivot
    below ``RANK_TOL``).  This is the factorisation behind the fast facet
    normals of algorithms.md ("W P = W_B [I F]").
    """
    n, m = W.shape
    scale = 0.0
    for i in range(n):
        for j in range(m):
            tab[i, j] = W[i, j]
            if abs(W[i, j]) > scale:
                scale = abs(W[i, j])
        for j in range(n):
            tab[i, m + j] = 1.0 if i == j else 0.0
    for j in range(m):
        slot[j] = -1
    # one return, at the end, and loops with one exit each: numba then counts no reference to the
    # arrays (an early return or a ``break`` kept a count per array per call)
    ok = scale != 0.0 and m >= n
    c = 0
    while ok and c < n:
        best = -1.0
        pr = -1
        pc = -1
        for i in range(c, n):
            for j in range(m):
                if slot[j] < 0 and abs(tab[i, j]) > best:
                    best = abs(tab[i, j])
                    pr = i
                    pc = j
        ok = best > RANK_TOL * scale
        if not ok:
            continue
        if pr != c:
            for j in range(m + n):
                tmp = tab[c, j]
                tab[c, j] = tab[pr, j]
                tab[pr, j] = tmp
        slot[pc] = c
        bcol[c] = pc
        inv = 1.0 / tab[c, pc]
        for j in range(m + n):
            tab[c, j] *= inv
        tab[c, pc] = 1.0
        for i in range(n):
            if i != c:
                f = tab[i, pc]
                if f != 0.0:
                    for j in range(m + n):
                        tab[i, j] -= f * tab[c, j]
                    tab[i, pc] = 0.0
        c += 1
    k = 0
    for j in range(m if ok else 0):
        if slot[j] < 0:
            nbc[k] = j
            k += 1
    return ok


@njit
def null_vector(A, k, mu, minor):
    """Null vector mu (k+1) of A (k, k+1) by the generalised cross product.

    mu_f = (-1)^f det(A without column f).  Returns False when A has rank < k
    (||mu|| below RANK_TOL times the Hadamard bound prod_e ||A_e||, compared
    squared).
    """
    if k == 0:
        mu[0] = 1.0
        return True
    if k == 1:
        mu[0] = A[0, 1]
        mu[1] = -A[0, 0]
    elif k == 2:
        mu[0] = A[0, 1] * A[1, 2] - A[0, 2] * A[1, 1]
        mu[1] = A[0, 2] * A[1, 0] - A[0, 0] * A[1, 2]
        mu[2] = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    else:
        sign = 1.0
        for f in range(k + 1):
            for e in range(k):
                cc = 0
                for g in range(k + 1):
                    if g == f:
                        continue
                    minor[e, cc] = A[e, g]
                    cc += 1
            mu[f] = sign * det_in_place(minor, k)  # minor is rebuilt for each f
            sign = -sign
    if k == 1:  # |mu| equals |A_0|: only a zero row makes it vanish
        return mu[0] != 0.0 or mu[1] != 0.0
    bound2 = 1.0
    for e in range(k):
        s = 0.0
        for g in range(k + 1):
            s += A[e, g] * A[e, g]
        bound2 *= s
    nrm2 = 0.0
    for f in range(k + 1):
        nrm2 += mu[f] * mu[f]
    return bound2 > 0.0 and nrm2 > RANK_TOL * RANK_TOL * bound2


@njit
def next_comb(idx, k, nn):
    """Advance idx[:k] to the next k-subset of range(nn) (lexicographic); False at the end."""
    i = k - 1
    while i >= 0 and idx[i] == nn - k + i:
        i -= 1
    if i < 0:
        return False
    idx[i] += 1
    for j in range(i + 1, k):
        idx[j] = idx[j - 1] + 1
    return True


@njit_fast
def hsm_factored(W, wreq, nv, tmin, tmax, scr, want_closure):
    """Capacity margins and wrench closure of the factored W: (margin0, margin, closure).

    :func:`hsm_enumerate`'s results; one or two redundant cables (m - n = 1,
    2) take the closed forms of :mod:`cdpr_design.kernels.hsm_small` (same
    facets, same tests), any other m the enumeration itself.  ``closure``
    means something only when ``want_closure`` (the closed forms skip the
    test otherwise).  The sweeps' pose function makes the same choice inline
    (:func:`cdpr_design.kernels.pose.eval_general`).
    """
    r = W.shape[1] - W.shape[0]
    if r == 2:
        return hsm_two(W, wreq, nv, tmin, tmax, scr, want_closure)
    if r == 1:
        return hsm_one(W, wreq, nv, tmin, tmax, scr, want_closure)
    return hsm_enumerate(W, wreq, nv, tmin, tmax, scr)


@njit_folded
def slot_dot(mu, X, Fr, nf, j):
    """sum_f mu[f] X[Fr[f], j] over a facet's ``nf`` free slots ``Fr`` (:func:`hsm_enumerate`):
    nu . x for column j of X = G x, e.g. l_j = nu . w_j for X the tableau's G W."""
    s = 0.0
    for f in range(nf):
        s += mu[f] * X[Fr[f], j]
    return s


@njit_folded
def facet_norm2(mu, M, Fr, nf):
    """||nu||^2 = mu^T M mu of a facet normal nu = G^T mu supported on the ``nf`` free slots ``Fr``,
    M = G G^T (:func:`hsm_enumerate`)."""
    nrm2 = 0.0
    for f in range(nf):
        sf = Fr[f]
        acc = 0.0
        for g in range(nf):
            acc += mu[g] * M[sf, Fr[g]]
        nrm2 += mu[f] * acc
    return nrm2


@njit_fast
def hsm_enumerate(W, wreq, nv, tmin, tmax, scr):
    """Hyperplane shifting on the factored W: capacity margins and wrench closure.

    Gouttefarde & Krut, ARK 2010; Bouchard, Gosselin & Moore, ASME JMR 2010
    (facets of the available wrench set); capacity margin after Guay, Cardou,
    Cruz-Ruiz & Caro 2014.  With W P = W_B [I F] and G = W_B^-1 (``scr[0]``
    = [G W | G], from :func:`basis_factor`), every subset S of n-1 columns is
    a set K of k non-basic columns (k <= m - n) plus the basis columns
    outside a set Fr of k+1 "free" slots; the C(m, n-1) facets are all pairs
    (K, Fr).  The facet normal is nu = G^T mu with mu supported on Fr and
    orthogonal to the rows Fr of F's columns K: a k x (k+1) null vector.  Then
    l_j = nu . w_j = mu . (G W)_j is mu_f for the basis column of slot f in
    Fr, zero for the other columns of S, and mu . F_c for a non-basic column c
    outside K; nu . w = mu . (G w) and ||nu||^2 = mu^T (G G^T) mu.  For every
    facet  s_S(w) = (1/2 sum_j |l_j| dt_j - |nu . (W t_mid - w)|) / ||nu||.

    Returns (margin0, margin, closure): the capacity margin [N] of
    ``wreq[0]`` alone, of the rows ``wreq[:nv]``, and whether W positively
    spans R^n (every facet hyperplane has columns strictly on both sides).
    Rank n is assumed: the caller factored W.
    """
    n, m = W.shape
    r = m - n
    tab, M, wh, wmid, A, minor, mu, ctol = scr[0], scr[1], scr[2], scr[3], scr[4], scr[5], scr[6], scr[7]
    nbc, bcol, Fr, Kc, dt = scr[19], scr[20], scr[22], scr[23], scr[27]
    # G w_v, G W t_mid, M = G G^T, closure tolerances, tension ranges
    for v in range(nv):
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += tab[i, m + j] * wreq[v, j]
            wh[v, i] = s
    for i in range(n):
        s = 0.0
        for j in range(m):
            s += tab[i, j] * 0.5 * (tmin[j] + tmax[j])
        wmid[i] = s
    gram_of_inverse(tab, n, m, M)
    for j in range(m):
        s = 0.0
        for i in range(n):
            s += W[i, j] * W[i, j]
        ctol[j] = CLOSURE_TOL * math.sqrt(s)
        dt[j] = tmax[j] - tmin[j]
    margin0 = np.inf
    margin = np.inf
    closure = True
    for k in range(min(r, n - 1) + 1):
        nf = k + 1
        for e in range(k):
            Kc[e] = e
        more_k = True
        while more_k:
            for f in range(nf):
                Fr[f] = f
            more_f = True
            while more_f:
                for e in range(k):
                    c = nbc[Kc[e]]
                    for f in range(nf):
                        A[e, f] = tab[Fr[f], c]
                if null_vector(A, k, mu, minor):
                    nrm2 = facet_norm2(mu, M, Fr, nf)
                    if nrm2 > 0.0:
                        nrm = math.sqrt(nrm2)
                        half = 0.0
                        lpos = -np.inf
                        lneg = np.inf
                        # basis columns of the free slots: l = mu_f
                        for f in range(nf):
                            j = bcol[Fr[f]]
                            lj = mu[f]
                            half += abs(lj) * dt[j]
                            lpos = max(lpos, lj - ctol[j] * nrm)
                            lneg = min(lneg, lj + ctol[j] * nrm)
                        # non-basic columns outside K (Kc is sorted)
                        e = 0
                        for q in range(r):
                            if e < k and Kc[e] == q:
                                e += 1
                                continue
                            j = nbc[q]
                            lj = slot_dot(mu, tab, Fr, nf, j)
                            half += abs(lj) * dt[j]
                            lpos = max(lpos, lj - ctol[j] * nrm)
                            lneg = min(lneg, lj + ctol[j] * nrm)
                        if not (lpos > 0.0 and lneg < 0.0):
                            closure = False
                        inv = 1.0 / nrm
                        half *= 0.5 * inv
                        cmid = 0.0
                        for f in range(nf):
                            cmid += mu[f] * wmid[Fr[f]]
                        for v in range(nv):
                            cw = 0.0
                            for f in range(nf):
                                cw += mu[f] * wh[v, Fr[f]]
                            s = half - abs(cmid - cw) * inv
                            if v == 0 and s < margin0:
                                margin0 = s
                            if s < margin:
                                margin = s
                more_f = next_comb(Fr, nf, n)
            more_k = next_comb(Kc, k, r)
    return margin0, margin, closure
