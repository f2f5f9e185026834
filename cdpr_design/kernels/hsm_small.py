"""Hyperplane shifting for one or two redundant cables (m - n = 1 or 2), facet by facet in closed form.

The same facets, margins and wrench-closure test as the general enumeration
:func:`cdpr_design.kernels.hsm.hsm_enumerate` (Gouttefarde & Krut, ARK 2010;
Bouchard, Gosselin & Moore, ASME JMR 2010; capacity margin after Guay,
Cardou, Cruz-Ruiz & Caro 2014), on the same basis factorisation
W P = W_B [I F], G = W_B^-1 (:func:`cdpr_design.kernels.hsm.basis_factor`).

With r = m - n <= 2 the complement T of a facet's n - 1 columns has only
r + 1 <= 3 columns, and l_j = nu . w_j vanishes outside T.  Every facet is
one of three kinds (k = number of non-basic columns inside the facet's
subset S, F_e = column of F of the non-basic column c_e, slots s, t, u):

=====  ===========================  ==========================================
k      T                            l on T (up to one common sign)
=====  ===========================  ==========================================
0      {s} + all non-basic          l_s = 1, l_ce = F_e[s]
1      {s, t} + the other (r = 2)   l_s = F_e[t], l_t = -F_e[s], l_co = mu . F_o
2      {s, t, u} (r = 2)            the 2 x 2 minors P_tu, P_us, P_st of [F_1 F_2]
=====  ===========================  ==========================================

with P_st = F_1[s] F_2[t] - F_1[t] F_2[s], computed once per pose for every
pair of slots.  The facet's free slots carry mu = l restricted to the basis
columns, so ||nu||^2 = mu^T (G G^T) mu and nu . (W t_mid - w) =
mu . G (W t_mid - w).  The rank tests are those of the enumeration (a zero
mu for k = 1; the Hadamard bound of the two rows of F on {s, t, u} for
k = 2), so both give the same facets and, to rounding, the same margins
(tested against :func:`~cdpr_design.kernels.hsm.hsm_enumerate` and a plain
SVD per subset).  Nothing is allocated: the scratch comes from
:func:`~cdpr_design.kernels.hsm.make_scratch`.
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.kernels._jit import njit_fast, njit_folded, njit_inline
from cdpr_design.kernels.linalg import CLOSURE_TOL, RANK_TOL, gram_of_inverse


@njit_fast
def facet_setup(W, wreq, nv, tmin, tmax, tab, M, e, sv, nbc, bcol, want_closure):
    """Per-pose quantities in basis-slot order, after M = G G^T (``M``, :func:`~cdpr_design.kernels.linalg.gram_of_inverse`):
    e_v = G (W t_mid - w_v) (``e`` row v),
    and per position p (slots 0..n-1, then the non-basic columns) the tension range ``sv[0, p]``
    and (``want_closure``) the closure tolerance ``sv[1, p]``."""
    n, m = W.shape
    for i in range(n):
        s = 0.0
        for j in range(m):
            s += tab[i, j] * 0.5 * (tmin[j] + tmax[j])
        for v in range(nv):
            g = 0.0
            for j in range(n):
                g += tab[i, m + j] * wreq[v, j]
            e[v, i] = s - g
    for p in range(m):
        j = bcol[p] if p < n else nbc[p - n]
        sv[0, p] = tmax[j] - tmin[j]
        sv[1, p] = 0.0
        if want_closure:
            s = 0.0
            for i in range(n):
                s += W[i, j] * W[i, j]
            sv[1, p] = CLOSURE_TOL * math.sqrt(s)


@njit_inline
def _width(la, lb, lc, da, db, dc, ka, kb, kc, nrm2, want_closure):
    """One facet's half width / ||nu||, 1 / ||nu|| and closure test, from scalars only.

    l = (``la``, ``lb``, ``lc``) on T with tension ranges ``d*`` and closure
    tolerances ``k*`` (a member with l = 0, d = k = 0 stands in for an
    absent third column).  Returns (half, inv, closes); inv = 0 when
    ||nu||^2 <= 0 (no facet).
    """
    if not nrm2 > 0.0:
        return 0.0, 0.0, True
    nrm = math.sqrt(nrm2)
    closes = True
    if want_closure:
        lpos = max(max(la - ka * nrm, lb - kb * nrm), lc - kc * nrm)
        lneg = min(min(la + ka * nrm, lb + kb * nrm), lc + kc * nrm)
        closes = lpos > 0.0 and lneg < 0.0
    inv = 1.0 / nrm
    return (abs(la) * da + abs(lb) * db + abs(lc) * dc) * (0.5 * inv), inv, closes


@njit_folded
def _other_rows(e, nv, a, b, c, la, lb, lc, half, inv, margin):
    """``margin`` lowered by rows 1..nv-1 of the required wrenches (centre l_a e_a + l_b e_b + l_c e_c)."""
    for v in range(1, nv):
        s = half - abs(la * e[v, a] + lb * e[v, b] + lc * e[v, c]) * inv
        margin = s if s < margin else margin
    return margin


@njit_fast
def hsm_one(W, wreq, nv, tmin, tmax, scr, want_closure):
    """:func:`~cdpr_design.kernels.hsm.hsm_enumerate` for m = n + 1: (margin0, margin, closure);
    ``closure`` is tested only when ``want_closure`` (else returned True).  ``scr`` from
    :func:`~cdpr_design.kernels.hsm.make_scratch`.  A pose's code calls the two functions
    itself, on the scratch's arrays (:func:`~cdpr_design.kernels.pose.eval_small`)."""
    gram_of_inverse(scr[0], W.shape[0], W.shape[1], scr[1])
    facet_setup(W, wreq, nv, tmin, tmax, scr[0], scr[1], scr[2], scr[28], scr[19], scr[20], want_closure)
    # the body compiled once, with the flag a variable: compiled with it a constant (a copy per
    # value) it cost a first run more compile and no measurable time a pose.  A
    # compiled function rather than an inlined body: numba's inlining copies a body's IR block
    # by block with its whole scope, quadratic in its size (docs/performance.md)
    return facets_one(W, wreq, nv, scr[0], scr[1], scr[2], scr[28], scr[29], scr[19], want_closure)


@njit_fast
def facets_one(W, wreq, nv, tab, M, e, sv, P, nbc, want_closure):
    """The facets of :func:`hsm_one` (``tab`` scr[0], ``M`` scr[1], ``e`` scr[2], ``sv`` scr[28],
    ``nbc`` scr[19]) after :func:`facet_setup`.  ``P`` (scr[29]) is not used: the arguments of :func:`facets_two`, so
    that a pose's code calls either alike (:func:`~cdpr_design.kernels.pose.eval_small`)."""
    n, m = W.shape
    c = nbc[0]
    margin0 = np.inf
    margin = np.inf
    closure = True
    for s in range(n):
        for t in range(s, n):
            if t == s:  # k = 0: T = {s, c}, l = (1, F[s])
                ls = 1.0
                lt = tab[s, c]
                nrm2 = M[s, s]
                half, inv, closes = _width(ls, lt, 0.0, sv[0, s], sv[0, n], 0.0, sv[1, s], sv[1, n], 0.0,
                                           nrm2, want_closure)
                lt = 0.0  # not a basis column: no centre term
            else:  # k = 1: T = {s, t}, mu = (F[t], -F[s])
                ls = tab[t, c]
                lt = -tab[s, c]
                if ls == 0.0 and lt == 0.0:
                    continue
                nrm2 = ls * ls * M[s, s] + 2.0 * ls * lt * M[s, t] + lt * lt * M[t, t]
                half, inv, closes = _width(ls, lt, 0.0, sv[0, s], sv[0, t], 0.0, sv[1, s], sv[1, t], 0.0,
                                           nrm2, want_closure)
            if inv == 0.0:
                continue
            closure = closure and closes
            x = half - abs(ls * e[0, s] + lt * e[0, t]) * inv
            margin0 = x if x < margin0 else margin0
            margin = x if x < margin else margin
            if nv > 1:
                margin = _other_rows(e, nv, s, t, s, ls, lt, 0.0, half, inv, margin)
    return margin0, margin, closure


@njit_fast
def hsm_two(W, wreq, nv, tmin, tmax, scr, want_closure):
    """:func:`~cdpr_design.kernels.hsm.hsm_enumerate` for m = n + 2: (margin0, margin, closure);
    ``closure`` is tested only when ``want_closure`` (else returned True).  ``scr`` from
    :func:`~cdpr_design.kernels.hsm.make_scratch`; see :func:`hsm_one`."""
    gram_of_inverse(scr[0], W.shape[0], W.shape[1], scr[1])
    facet_setup(W, wreq, nv, tmin, tmax, scr[0], scr[1], scr[2], scr[28], scr[19], scr[20], want_closure)
    return facets_two(W, wreq, nv, scr[0], scr[1], scr[2], scr[28], scr[29], scr[19], want_closure)


@njit_fast
def facets_two(W, wreq, nv, tab, M, e, sv, P, nbc, want_closure):
    """The facets of :func:`hsm_two` (``tab`` scr[0], ``M`` scr[1], ``e`` scr[2], ``sv`` scr[28], ``P``
    scr[29], ``nbc`` scr[19]) after :func:`facet_setup`."""
    n, m = W.shape
    c1 = nbc[0]
    c2 = nbc[1]
    for s in range(n):
        for t in range(s + 1, n):
            P[s, t] = tab[s, c1] * tab[t, c2] - tab[t, c1] * tab[s, c2]
            P[t, s] = -P[s, t]
    margin0 = np.inf
    margin = np.inf
    closure = True
    for s in range(n):  # k = 0: T = {s, c1, c2}, l = (1, F_1[s], F_2[s])
        half, inv, closes = _width(1.0, tab[s, c1], tab[s, c2], sv[0, s], sv[0, n], sv[0, n + 1],
                                   sv[1, s], sv[1, n], sv[1, n + 1], M[s, s], want_closure)
        if inv == 0.0:
            continue
        closure = closure and closes
        x = half - abs(e[0, s]) * inv
        margin0 = x if x < margin0 else margin0
        margin = x if x < margin else margin
        if nv > 1:
            margin = _other_rows(e, nv, s, s, s, 1.0, 0.0, 0.0, half, inv, margin)
    for s in range(n):  # k = 1: K = {c_e}, T = {s, t, c_o}, mu = (F_e[t], -F_e[s])
        for t in range(s + 1, n):
            for ke in range(2):
                ce = c1 if ke == 0 else c2
                ls = tab[t, ce]
                lt = -tab[s, ce]
                if ls == 0.0 and lt == 0.0:
                    continue
                lo = P[s, t] if ke == 1 else -P[s, t]
                po = n + 1 - ke
                nrm2 = ls * ls * M[s, s] + 2.0 * ls * lt * M[s, t] + lt * lt * M[t, t]
                half, inv, closes = _width(ls, lt, lo, sv[0, s], sv[0, t], sv[0, po], sv[1, s], sv[1, t], sv[1, po],
                                           nrm2, want_closure)
                if inv == 0.0:
                    continue
                closure = closure and closes
                x = half - abs(ls * e[0, s] + lt * e[0, t]) * inv
                margin0 = x if x < margin0 else margin0
                margin = x if x < margin else margin
                if nv > 1:
                    margin = _other_rows(e, nv, s, t, s, ls, lt, 0.0, half, inv, margin)
    for s in range(n):  # k = 2: T = {s, t, u}, mu = (P_tu, P_us, P_st)
        for t in range(s + 1, n):
            for u in range(t + 1, n):
                ls = P[t, u]
                lt = P[u, s]
                lu = P[s, t]
                a0 = tab[s, c1] * tab[s, c1] + tab[t, c1] * tab[t, c1] + tab[u, c1] * tab[u, c1]
                a1 = tab[s, c2] * tab[s, c2] + tab[t, c2] * tab[t, c2] + tab[u, c2] * tab[u, c2]
                bound2 = a0 * a1
                if not (bound2 > 0.0 and ls * ls + lt * lt + lu * lu > RANK_TOL * RANK_TOL * bound2):
                    continue
                nrm2 = (ls * ls * M[s, s] + lt * lt * M[t, t] + lu * lu * M[u, u]
                        + 2.0 * (ls * lt * M[s, t] + ls * lu * M[s, u] + lt * lu * M[t, u]))
                half, inv, closes = _width(ls, lt, lu, sv[0, s], sv[0, t], sv[0, u], sv[1, s], sv[1, t], sv[1, u],
                                           nrm2, want_closure)
                if inv == 0.0:
                    continue
                closure = closure and closes
                x = half - abs(ls * e[0, s] + lt * e[0, t] + lu * e[0, u]) * inv
                margin0 = x if x < margin0 else margin0
                margin = x if x < margin else margin
                if nv > 1:
                    margin = _other_rows(e, nv, s, t, u, ls, lt, lu, half, inv, margin)
    return margin0, margin, closure
