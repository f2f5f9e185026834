"""Every numba kernel of cdpr-design, in one place.

Kernels take contiguous float64 arrays in SI units and never model objects.
Conventions (see ``shared/design/spec-format.md``):

- full pose ``[x, y, z, rx, ry, rz]``, R = Rx(rx) Ry(ry) Rz(rz);
- full wrench ``[fx, fy, fz, mx, my, mz]``; ``rows`` picks the balanced rows;
- cable vector l_i = a_i - (p + R b_i), u_i = l_i / |l_i| (pulls towards the outlet);
- structure matrix column i = [u_i ; (R b_i) x u_i][rows].

The jit options are set here once (``cache=True`` so users pay the compile
time once per machine, ``nogil`` so sweeps can run in threads).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

JIT = dict(cache=True, nogil=True, error_model="numpy")
njit = nb.njit(**JIT)
njit_parallel = nb.njit(parallel=True, **JIT)
#: Reassociation (vectorised reductions) without giving up NaN/inf semantics.
njit_fast = nb.njit(fastmath={"reassoc", "contract", "arcp"}, **JIT)

#: Relative tolerance below which a facet normal or a pivot counts as zero.
RANK_TOL = 1e-10

KIND_STATIC = 0
KIND_WRENCH_FEASIBLE = 1
KIND_WRENCH_CLOSURE = 2


# ----------------------------------------------------------------------------
# Kinematics
# ----------------------------------------------------------------------------


@njit
def rotation(rx, ry, rz, R):
    """R = Rx(rx) Ry(ry) Rz(rz) written into ``R`` (3, 3)."""
    cx, sx = math.cos(rx), math.sin(rx)
    cy, sy = math.cos(ry), math.sin(ry)
    cz, sz = math.cos(rz), math.sin(rz)
    R[0, 0] = cy * cz
    R[0, 1] = -cy * sz
    R[0, 2] = sy
    R[1, 0] = sx * sy * cz + cx * sz
    R[1, 1] = -sx * sy * sz + cx * cz
    R[1, 2] = -sx * cy
    R[2, 0] = -cx * sy * cz + sx * sz
    R[2, 1] = cx * sy * sz + sx * cz
    R[2, 2] = cx * cy


@njit
def rotate_attachments(R, B, Rb):
    """Rb[i] = R @ B[i] for every attachment."""
    for i in range(B.shape[0]):
        for r in range(3):
            Rb[i, r] = R[r, 0] * B[i, 0] + R[r, 1] * B[i, 1] + R[r, 2] * B[i, 2]


@njit
def structure_matrix(px, py, pz, Rb, A, rows, W, L):
    """Fill the structure matrix ``W`` (n, m) and lengths ``L`` (m) at one pose.

    Column i is [u_i ; (R b_i) x u_i] restricted to ``rows`` (spec-format.md,
    paper eq. 9).  Returns False when a cable has zero length (its direction
    is undefined); that column of ``W`` is then zero.
    """
    m = A.shape[0]
    n = rows.shape[0]
    ok = True
    for i in range(m):
        lx = A[i, 0] - px - Rb[i, 0]
        ly = A[i, 1] - py - Rb[i, 1]
        lz = A[i, 2] - pz - Rb[i, 2]
        li = math.sqrt(lx * lx + ly * ly + lz * lz)
        L[i] = li
        if li <= 1e-12:
            ok = False
            for k in range(n):
                W[k, i] = 0.0
            continue
        fill_column(W, i, rows, lx / li, ly / li, lz / li, Rb[i, 0], Rb[i, 1], Rb[i, 2])
    return ok


@njit
def fill_column(W, i, rows, ux, uy, uz, bx, by, bz):
    """Column i of the structure matrix: [u ; (R b) x u] restricted to ``rows``."""
    for k in range(rows.shape[0]):
        r = rows[k]
        if r == 0:
            W[k, i] = ux
        elif r == 1:
            W[k, i] = uy
        elif r == 2:
            W[k, i] = uz
        elif r == 3:
            W[k, i] = by * uz - bz * uy
        elif r == 4:
            W[k, i] = bz * ux - bx * uz
        else:
            W[k, i] = bx * uy - by * ux


# ----------------------------------------------------------------------------
# Small dense linear algebra
# ----------------------------------------------------------------------------


@njit
def det_small(M, k):
    """Determinant of the leading k x k block of ``M`` (copied; partial pivoting)."""
    a = np.empty((k, k))
    for i in range(k):
        for j in range(k):
            a[i, j] = M[i, j]
    d = 1.0
    for c in range(k):
        piv = c
        best = abs(a[c, c])
        for r in range(c + 1, k):
            if abs(a[r, c]) > best:
                best = abs(a[r, c])
                piv = r
        if best == 0.0:
            return 0.0
        if piv != c:
            for j in range(k):
                tmp = a[c, j]
                a[c, j] = a[piv, j]
                a[piv, j] = tmp
            d = -d
        d *= a[c, c]
        for r in range(c + 1, k):
            f = a[r, c] / a[c, c]
            for j in range(c + 1, k):
                a[r, j] -= f * a[c, j]
    return d


@njit
def inverse_small(W, Winv):
    """Invert the square ``W`` (n, n) into ``Winv`` by Gauss-Jordan with pivoting.

    Returns False when W is singular to working precision (relative pivot
    below ``RANK_TOL``).
    """
    n = W.shape[0]
    a = np.empty((n, 2 * n))
    scale = 0.0
    for i in range(n):
        for j in range(n):
            a[i, j] = W[i, j]
            a[i, n + j] = 1.0 if i == j else 0.0
            if abs(W[i, j]) > scale:
                scale = abs(W[i, j])
    if scale == 0.0:
        return False
    for c in range(n):
        piv = c
        best = abs(a[c, c])
        for r in range(c + 1, n):
            if abs(a[r, c]) > best:
                best = abs(a[r, c])
                piv = r
        if best <= RANK_TOL * scale:
            return False
        if piv != c:
            for j in range(2 * n):
                tmp = a[c, j]
                a[c, j] = a[piv, j]
                a[piv, j] = tmp
        inv = 1.0 / a[c, c]
        for j in range(2 * n):
            a[c, j] *= inv
        for r in range(n):
            if r != c and a[r, c] != 0.0:
                f = a[r, c]
                for j in range(2 * n):
                    a[r, j] -= f * a[c, j]
    for i in range(n):
        for j in range(n):
            Winv[i, j] = a[i, n + j]
    return True


# ----------------------------------------------------------------------------
# Square systems (m = n): closed forms
# ----------------------------------------------------------------------------


@njit
def square_eval(W, wreq, tmin, tmax, t):
    """Tensions and capacity margin of a square structure matrix.

    For m = n the tensions are unique, t = W^-1 w, and the capacity margin is
    min_i min(t_i - t_min,i, t_max,i - t_i) / ||row_i(W^-1)||_2, minimised over
    the required-wrench vertices (rows of ``wreq``); ``t`` receives the
    tensions for the first vertex.  Returns (rank_ok, margin).  This equals the
    hyperplane-shifting margin (the facet normals of a parallelotope are the
    rows of W^-1).
    """
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
    Winv = np.empty((n, n))
    if not inverse_small(W, Winv):
        for i in range(n):
            t[i] = np.nan
        return False, np.nan
    rn = np.empty(n)
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


# ----------------------------------------------------------------------------
# Hyperplane shifting: capacity margin for any m >= n
# ----------------------------------------------------------------------------


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


@njit
def hsm_margin(W, wreq, tmin, tmax, combos):
    """Capacity margin by the hyperplane shifting method.

    Gouttefarde & Krut, ARK 2010; Bouchard, Gosselin & Moore, ASME JMR 2010;
    Guay et al. 2014 (capacity margin).  For every subset S of n-1 columns of
    rank n-1, with unit normal nu and l_j = nu . w_j:

        s_S(w) = 1/2 sum_j |l_j| (t_max,j - t_min,j) - |nu . (W t_mid - w)|

    The margin is min over S and over the required-wrench vertices ``wreq``
    (nv, n).  Returns (rank_ok, margin); rank_ok is False (margin NaN) when W
    has rank < n.  A negative margin is the largest facet violation.
    """
    n, m = W.shape
    nv = wreq.shape[0]
    nu = np.empty(n)
    wmid = np.empty(n)
    for i in range(n):
        s = 0.0
        for j in range(m):
            s += W[i, j] * 0.5 * (tmin[j] + tmax[j])
        wmid[i] = s
    rank_ok = False
    margin = np.inf
    for c in range(combos.shape[0]):
        if not facet_normal(W, combos[c], nu):
            continue
        half = 0.0
        lmax = 0.0
        for j in range(m):
            lj = 0.0
            for i in range(n):
                lj += nu[i] * W[i, j]
            lj = abs(lj)
            if lj > lmax:
                lmax = lj
            half += 0.5 * lj * (tmax[j] - tmin[j])
        if lmax > RANK_TOL:
            rank_ok = True
        cmid = 0.0
        for i in range(n):
            cmid += nu[i] * wmid[i]
        for k in range(nv):
            cw = 0.0
            for i in range(n):
                cw += nu[i] * wreq[k, i]
            s = half - abs(cmid - cw)
            if s < margin:
                margin = s
    if not rank_ok:
        return False, np.nan
    return True, margin


# ----------------------------------------------------------------------------
# General m != n: basis factorisation, fast HSM, wrench closure, min-norm QP
# ----------------------------------------------------------------------------

#: Relative tolerance of the wrench-closure sign test (|l_j| against |w_j|).
CLOSURE_TOL = 1e-12
#: Relative tolerance (to the largest tension bound) of the QP's bound checks.
QP_TOL = 1e-11


@njit
def make_scratch(n, m, nv):
    """Scratch arrays for :func:`eval_general` (allocate once per block of poses).

    A tuple so that every array keeps its contiguous type; ``nv`` is the
    number of required-wrench rows.
    """
    r = max(m - n, 1)
    return (np.empty((n, m + n)),       # 0 tab: [G W | G], G = W_B^-1
            np.empty((n, n)),           # 1 M = G G^T
            np.empty((max(nv, 1), n)),  # 2 G w_v
            np.empty(n),                # 3 G W t_mid
            np.empty((n, n)),           # 4 A (k, k+1)
            np.empty((n, n)),           # 5 minor
            np.empty(n + 1),            # 6 mu
            np.empty(m),                # 7 closure tolerance per column
            np.empty((m, r)),           # 8 N, orthonormal null basis
            np.empty(m),                # 9 t_p
            np.empty((r, r)),           # 10 J
            np.empty((r, r)),           # 11 R of the active normals
            np.empty((r, r)),           # 12 active normals
            np.empty((r, r)),           # 13 Householder vectors
            np.empty(r),                # 14 z
            np.empty(r),                # 15 d
            np.empty(r),                # 16 dual direction
            np.empty(r + 1),            # 17 multipliers
            np.empty(m, dtype=np.int64),      # 18 slot of each column (-1: non-basic)
            np.empty(max(m - n, 1), dtype=np.int64),  # 19 non-basic columns
            np.empty(n, dtype=np.int64),      # 20 basis column of each slot
            np.empty(n, dtype=np.int64),      # 21 (spare)
            np.empty(n, dtype=np.int64),      # 22 facet: free slots
            np.empty(n, dtype=np.int64),      # 23 facet: non-basic columns of S (positions in nbc)
            np.empty(2 * m + 1, dtype=np.int64),  # 24 active constraints
            np.empty(m),                # 25 t_b (basic solution)
            np.empty(m),                # 26 facet: l_j
            np.empty(m))                # 27 t_max - t_min


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
    if scale == 0.0 or m < n:
        return False
    for c in range(n):
        best = -1.0
        pr = -1
        pc = -1
        for i in range(c, n):
            for j in range(m):
                if slot[j] < 0 and abs(tab[i, j]) > best:
                    best = abs(tab[i, j])
                    pr = i
                    pc = j
        if best <= RANK_TOL * scale:
            return False
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
    k = 0
    for j in range(m):
        if slot[j] < 0:
            nbc[k] = j
            k += 1
    return True


@njit
def _null_vector(A, k, mu, minor):
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
            mu[f] = sign * det_small(minor, k)
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
def _next_comb(idx, k, nn):
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
def hsm_factored(W, wreq, nv, tmin, tmax, scr):
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
    for i in range(n):
        for j in range(i, n):
            s = 0.0
            for k in range(n):
                s += tab[i, m + k] * tab[j, m + k]
            M[i, j] = s
            M[j, i] = s
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
                if _null_vector(A, k, mu, minor):
                    nrm2 = 0.0
                    for f in range(nf):
                        sf = Fr[f]
                        acc = 0.0
                        for g in range(nf):
                            acc += mu[g] * M[sf, Fr[g]]
                        nrm2 += mu[f] * acc
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
                            lj = 0.0
                            for f in range(nf):
                                lj += mu[f] * tab[Fr[f], j]
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
                more_f = _next_comb(Fr, nf, n)
            more_k = _next_comb(Kc, k, r)
    return margin0, margin, closure


@njit
def householder_qr(A, p, q, Q, R, V):
    """Full QR of the leading (p, q) block of ``A`` (p >= q): A = Q [R; 0].

    ``A`` is overwritten; ``Q`` (p, p) orthogonal, ``R`` (q, q) upper
    triangular, ``V`` (p, q) scratch for the reflectors.  Returns the
    smallest |R_ii| (inf for q = 0).
    """
    rmin = np.inf
    for c in range(q):
        s = 0.0
        for i in range(c, p):
            s += A[i, c] * A[i, c]
        nx = math.sqrt(s)
        alpha = -nx if A[c, c] >= 0.0 else nx
        for i in range(c, p):
            V[i, c] = A[i, c]
        V[c, c] -= alpha
        vn = 0.0
        for i in range(c, p):
            vn += V[i, c] * V[i, c]
        if vn > 0.0:
            vn = math.sqrt(vn)
            for i in range(c, p):
                V[i, c] /= vn
            for j in range(c, q):
                d = 0.0
                for i in range(c, p):
                    d += V[i, c] * A[i, j]
                for i in range(c, p):
                    A[i, j] -= 2.0 * V[i, c] * d
        for i in range(c + 1, p):
            A[i, c] = 0.0
        if abs(A[c, c]) < rmin:
            rmin = abs(A[c, c])
    for i in range(q):
        for j in range(q):
            R[i, j] = A[i, j] if j >= i else 0.0
    for i in range(p):
        for j in range(p):
            Q[i, j] = 1.0 if i == j else 0.0
    for c in range(q - 1, -1, -1):
        for j in range(p):
            d = 0.0
            for i in range(c, p):
                d += V[i, c] * Q[i, j]
            if d != 0.0:
                for i in range(c, p):
                    Q[i, j] -= 2.0 * V[i, c] * d
    return rmin


@njit
def null_space_setup(n, m, w, scr):
    """Orthonormal null basis N (m, r) and t_p = W^+ w from the basis factorisation.

    The columns of P [-F; I] span the null space of W; two passes of
    classical Gram-Schmidt make them orthonormal (``scr[8]``).  The basic
    solution t_b (t_B = G w, t_N = 0) projected off the null space is the
    minimum-norm solution t_p = t_b - N N^T t_b (``scr[9]``).
    """
    tab, N, tp, tb = scr[0], scr[8], scr[9], scr[25]
    nbc, bcol = scr[19], scr[20]
    r = m - n
    for k in range(r):
        col = nbc[k]
        for j in range(m):
            N[j, k] = 0.0
        N[col, k] = 1.0
        for s in range(n):
            N[bcol[s], k] = -tab[s, col]
        for _ in range(2):
            for p in range(k):
                d = 0.0
                for j in range(m):
                    d += N[j, p] * N[j, k]
                for j in range(m):
                    N[j, k] -= d * N[j, p]
        s = 0.0
        for j in range(m):
            s += N[j, k] * N[j, k]
        s = 1.0 / math.sqrt(s)
        for j in range(m):
            N[j, k] *= s
    for j in range(m):
        tb[j] = 0.0
    for s in range(n):
        acc = 0.0
        for i in range(n):
            acc += tab[s, m + i] * w[i]
        tb[bcol[s]] = acc
    for j in range(m):
        tp[j] = tb[j]
    for k in range(r):
        d = 0.0
        for j in range(m):
            d += N[j, k] * tb[j]
        for j in range(m):
            tp[j] -= d * N[j, k]


@njit
def _refactor(N, m, r, active, q, J, RA, NA, VA):
    """QR of the active constraint normals N_A (r, q) = J [R; 0]."""
    for a in range(q):
        c = active[a]
        j = c % m
        sg = 1.0 if c < m else -1.0
        for i in range(r):
            NA[i, a] = sg * N[j, i]
    householder_qr(NA, r, q, J, RA, VA)


@njit
def goldfarb_idnani(m, r, tmin, tmax, t, scr):
    """Project the origin onto {z : t_min <= t_p + N z <= t_max}; t = t_p + N z.

    The dual active-set method of Goldfarb & Idnani (Math. Programming 27,
    1983) with G = I: start at the unconstrained minimum z = 0, add the most
    violated bound, take the primal/dual step, drop a constraint whose
    multiplier would turn negative.  A violated constraint whose normal lies
    in the span of the active ones and whose dual step is unbounded proves
    the bounds infeasible.  The active normals are re-factored by a
    Householder QR at each change (r = m - n is small: cheaper and sturdier
    than Givens bookkeeping).  Violations below ``QP_TOL`` times the largest
    bound count as satisfied; the result is clipped into the bounds.
    Returns False (``t`` NaN) when infeasible.
    """
    N, tp, J, RA, NA, VA = scr[8], scr[9], scr[10], scr[11], scr[12], scr[13]
    z, d, rdir, u, active = scr[14], scr[15], scr[16], scr[17], scr[24]
    scale = 1.0
    for j in range(m):
        scale = max(scale, max(abs(tmin[j]), abs(tmax[j])))
    tol = QP_TOL * scale
    for i in range(r):
        z[i] = 0.0
        for k in range(r):
            J[i, k] = 1.0 if i == k else 0.0
    q = 0
    maxit = 20 * (2 * m + r) + 50
    it = 0
    feasible = True
    while True:
        # most violated bound: t_j - tmin_j (c < m) or tmax_j - t_j (c >= m)
        p = -1
        sp = -tol
        for j in range(m):
            tj = tp[j]
            for i in range(r):
                tj += N[j, i] * z[i]
            sl = tj - tmin[j]
            su = tmax[j] - tj
            if sl < sp or su < sp:
                c = j if sl < su else j + m
                isact = False
                for a in range(q):
                    if active[a] == c:
                        isact = True
                        break
                if not isact:
                    sp = min(sl, su)
                    p = c
        if p < 0:
            break
        up = 0.0
        jp = p % m
        sg = 1.0 if p < m else -1.0
        while True:
            it += 1
            if it > maxit:
                feasible = False
                break
            # d = J^T a_p with a_p = sg N[jp, :]
            for i in range(r):
                s = 0.0
                for k in range(r):
                    s += J[k, i] * N[jp, k]
                d[i] = sg * s
            # dual direction R^-1 d[:q]
            for i in range(q - 1, -1, -1):
                s = d[i]
                for k in range(i + 1, q):
                    s -= RA[i, k] * rdir[k]
                rdir[i] = s / RA[i, i]
            dd = 0.0
            for i in range(q, r):
                dd += d[i] * d[i]
            t1 = np.inf
            ldrop = -1
            for a in range(q):
                if rdir[a] > 1e-14:
                    ratio = u[a] / rdir[a]
                    if ratio < t1:
                        t1 = ratio
                        ldrop = a
            t2 = -sp / dd if dd > 1e-24 else np.inf
            if t1 == np.inf and t2 == np.inf:
                feasible = False
                break
            if t2 < np.inf:
                step = min(t1, t2)
                for i in range(r):
                    s = 0.0
                    for k in range(q, r):
                        s += J[i, k] * d[k]
                    z[i] += step * s
                sp += step * dd
            else:
                step = t1
            for a in range(q):
                u[a] -= step * rdir[a]
            up += step
            if t2 <= t1:
                active[q] = p
                u[q] = up
                q += 1
                _refactor(N, m, r, active, q, J, RA, NA, VA)
                break
            for a in range(ldrop, q - 1):
                active[a] = active[a + 1]
                u[a] = u[a + 1]
            q -= 1
            _refactor(N, m, r, active, q, J, RA, NA, VA)
        if not feasible:
            break
    if not feasible:
        for j in range(m):
            t[j] = np.nan
        return False
    for j in range(m):
        s = tp[j]
        for i in range(r):
            s += N[j, i] * z[i]
        t[j] = min(max(s, tmin[j]), tmax[j])
    return True


@njit
def min_norm_tensions(W, w, tmin, tmax, t, scr):
    """Minimum 2-norm tensions with bounds: min 1/2 |t|^2, W t = w, t_min <= t <= t_max.

    The null-space reduction of algorithms.md: t = t_p + N z with t_p = W^+ w
    and N an orthonormal null basis, so |t|^2 = |t_p|^2 + |z|^2 and the QP is
    the projection of the origin onto an r-dimensional polytope, solved
    exactly by :func:`goldfarb_idnani`.  Writes ``t`` (m) [N]; returns False
    (``t`` NaN) when the bounds admit no solution or rank W < n.  ``scr``
    from :func:`make_scratch`.
    """
    n, m = W.shape
    for j in range(m):
        t[j] = np.nan
    if not basis_factor(W, scr[0], scr[18], scr[19], scr[20]):
        return False
    null_space_setup(n, m, w, scr)
    return goldfarb_idnani(m, m - n, tmin, tmax, t, scr)


@njit
def eval_general(W, wreq, tmin, tmax, combos, kind, t_out, scr):
    """:func:`eval_pose` for any m >= n with caller-provided scratch (no allocation).

    ``scr`` comes from :func:`make_scratch` (n, m, wreq rows).  The margin is
    the fast hyperplane-shifting one (:func:`hsm_factored`) over ``wreq[0]``
    (static) or every row (wrench-feasible, wrench-closure); the tensions at
    ``wreq[0]`` come from the exact QP (:func:`goldfarb_idnani`), run only
    where the margin of ``wreq[0]`` is >= 0.  Static and wrench-feasible
    poses are feasible when the margin is >= 0 *and* the QP found tensions,
    so a feasible pose always has tensions; wrench-closure poses when W
    positively spans R^n.  Rank W < n or a zero column (zero-length cable):
    (False, NaN), tensions NaN.
    """
    n, m = W.shape
    nv = wreq.shape[0] if kind != KIND_STATIC else 1
    for i in range(m):
        t_out[i] = np.nan
    for j in range(m):
        s = 0.0
        for i in range(n):
            s += W[i, j] * W[i, j]
        if s == 0.0:
            return False, np.nan
    if not basis_factor(W, scr[0], scr[18], scr[19], scr[20]):
        return False, np.nan
    margin0, margin, closure = hsm_factored(W, wreq, nv, tmin, tmax, scr)
    qp_ok = False
    if margin0 >= 0.0:
        if m == n:
            # unique tensions t = G w
            tab = scr[0]
            bcol = scr[20]
            qp_ok = True
            for s in range(n):
                acc = 0.0
                for i in range(n):
                    acc += tab[s, m + i] * wreq[0, i]
                t_out[bcol[s]] = min(max(acc, tmin[bcol[s]]), tmax[bcol[s]])
        else:
            null_space_setup(n, m, wreq[0], scr)
            qp_ok = goldfarb_idnani(m, m - n, tmin, tmax, t_out, scr)
    if kind == KIND_WRENCH_CLOSURE:
        return closure and m > n, margin
    return margin >= 0.0 and qp_ok, margin


# ----------------------------------------------------------------------------
# Per-pose evaluation and the grid sweep
# ----------------------------------------------------------------------------


@njit
def eval_pose(W, wreq, tmin, tmax, combos, kind, t_out):
    """Feasibility, capacity margin and tensions of one pose.

    Parameters
    ----------
    W : (n, m) structure matrix.
    wreq : (nv, n) required-wrench vertices [N, N m]; row 0 is the nominal
        wrench (gravity only), the one whose tensions are reported.
    tmin, tmax : (m,) tension bounds [N].
    combos : (C(m, n-1), n-1) int64, the column subsets of the HSM.
    kind : KIND_STATIC (row 0 only), KIND_WRENCH_FEASIBLE (every row),
        KIND_WRENCH_CLOSURE (positive spanning, bounds ignored).
    t_out : (m,) receives the minimum 2-norm feasible tensions for row 0 [N]
        (NaN where there are none).

    Returns
    -------
    (feasible, margin) : margin is NaN where rank W < n.
    """
    n, m = W.shape
    nv = wreq.shape[0] if kind == KIND_WRENCH_FEASIBLE else 1
    for i in range(m):
        t_out[i] = np.nan
    if m == n:
        rank_ok, margin = square_eval(W, wreq[:nv], tmin, tmax, t_out)
        if not rank_ok:
            return False, np.nan
        # t = W^-1 w is unique: it is the tension distribution where it
        # respects the bounds, and there is none otherwise
        for i in range(m):
            if not (tmin[i] <= t_out[i] <= tmax[i]):
                for j in range(m):
                    t_out[j] = np.nan
                break
        # m = n columns can never positively span R^n: no wrench closure
        feasible = kind != KIND_WRENCH_CLOSURE and margin >= 0.0
        return feasible, margin
    # any m != n: basis-factored HSM + exact Goldfarb-Idnani min-norm QP
    # (allocates its scratch: sweeps call eval_general with per-block scratch)
    return eval_general(W, wreq, tmin, tmax, combos, kind, t_out,
                        make_scratch(n, m, wreq.shape[0]))


@njit_parallel
def sweep_grid(start, count, lower, step, shape, Rb, A, rows, wreq, tmin, tmax, combos,
               kind, feasible, margin, tensions, lengths):
    """Evaluate ``count`` grid poses from flat index ``start`` (C order over x, y, z).

    Outputs are written to rows 0..count-1 of ``feasible`` (uint8), ``margin``,
    ``tensions`` (count, m) and ``lengths`` (count, m).  The orientation is
    fixed: ``Rb`` holds R b_i.  Work is split into blocks, each with its own
    scratch arrays, so no allocation happens per pose.
    """
    n = rows.shape[0]
    m = A.shape[0]
    nblocks = min(count, 256)
    if nblocks == 0:
        return
    bsize = (count + nblocks - 1) // nblocks
    ny = shape[1]
    nz = shape[2]
    for b in nb.prange(nblocks):
        W = np.empty((n, m))
        t = np.empty(m)
        L = np.empty(m)
        scr = make_scratch(n, m, wreq.shape[0])  # general m != n kernels
        k0 = b * bsize
        k1 = min(count, k0 + bsize)
        # grid indices of the block's first pose, then counted up (no division per pose)
        idx = start + k0
        iz = idx % nz
        r = idx // nz
        iy = r % ny
        ix = r // ny
        for k in range(k0, k1):
            px = lower[0] + ix * step[0]
            py = lower[1] + iy * step[1]
            pz = lower[2] + iz * step[2]
            iz += 1
            if iz == nz:
                iz = 0
                iy += 1
                if iy == ny:
                    iy = 0
                    ix += 1
            ok = structure_matrix(px, py, pz, Rb, A, rows, W, L)
            for i in range(m):
                lengths[k, i] = L[i]
            if not ok:
                feasible[k] = 0
                margin[k] = np.nan
                for i in range(m):
                    tensions[k, i] = np.nan
                continue
            if m == n:
                f, mg = eval_pose(W, wreq, tmin, tmax, combos, kind, t)
            else:
                f, mg = eval_general(W, wreq, tmin, tmax, combos, kind, t, scr)
            feasible[k] = 1 if f else 0
            margin[k] = mg + 0.0  # -0.0 -> 0.0: one zero in the CSV, whatever the engine
            for i in range(m):
                tensions[k, i] = t[i]


@njit_parallel
def sweep_grid_planar2(start, count, lower, step, shape, Rb, A, wreq, tmin, tmax,
                       feasible, margin, tensions, lengths):
    """:func:`sweep_grid` specialised to two cables and two wrench rows (2T, m = n = 2).

    The seed paper's robot: everything inlined in closed form.  With
    u_i the unit cable vectors, det = u1x u2y - u2x u1y,
    t1 = (w_x u2y - w_y u2x) / det, t2 = (u1x w_y - u1y w_x) / det
    (algorithms.md; paper eq. 6-9), and the capacity margin is
    min_i min(t_i - t_min,i, t_max,i - t_i) / ||row_i(W^-1)||.
    Only the nominal wrench (row 0 of ``wreq``) is evaluated, plus the other
    rows for the margin when there are several (wrench-feasible sweeps).
    Same outputs as :func:`sweep_grid`.
    """
    nblocks = min(count, 256)
    if nblocks == 0:
        return
    bsize = (count + nblocks - 1) // nblocks
    ny = shape[1]
    nz = shape[2]
    nv = wreq.shape[0]
    a0x = A[0, 0] - Rb[0, 0]
    a0y = A[0, 1] - Rb[0, 1]
    a1x = A[1, 0] - Rb[1, 0]
    a1y = A[1, 1] - Rb[1, 1]
    # scalars hoisted out of the loop: the outputs could alias these arrays,
    # which would otherwise force a reload per pose
    w0 = wreq[0, 0]
    w1 = wreq[0, 1]
    tn0 = tmin[0]
    tn1 = tmin[1]
    tx0 = tmax[0]
    tx1 = tmax[1]
    for b in nb.prange(nblocks):
        k0 = b * bsize
        k1 = min(count, k0 + bsize)
        idx = start + k0
        iz = idx % nz
        r = idx // nz
        iy = r % ny
        ix = r // ny
        for k in range(k0, k1):
            px = lower[0] + ix * step[0]
            py = lower[1] + iy * step[1]
            iz += 1
            if iz == nz:
                iz = 0
                iy += 1
                if iy == ny:
                    iy = 0
                    ix += 1
            lx0 = a0x - px
            ly0 = a0y - py
            lx1 = a1x - px
            ly1 = a1y - py
            L0 = math.sqrt(lx0 * lx0 + ly0 * ly0)
            L1 = math.sqrt(lx1 * lx1 + ly1 * ly1)
            lengths[k, 0] = L0
            lengths[k, 1] = L1
            if L0 <= 1e-12 or L1 <= 1e-12:
                feasible[k] = 0
                margin[k] = np.nan
                tensions[k, 0] = np.nan
                tensions[k, 1] = np.nan
                continue
            u0x = lx0 / L0
            u0y = ly0 / L0
            u1x = lx1 / L1
            u1y = ly1 / L1
            det = u0x * u1y - u1x * u0y
            if abs(det) <= RANK_TOL:
                feasible[k] = 0
                margin[k] = np.nan
                tensions[k, 0] = np.nan
                tensions[k, 1] = np.nan
                continue
            inv = 1.0 / det
            i00 = u1y * inv
            i01 = -u1x * inv
            i10 = -u0y * inv
            i11 = u0x * inv
            r0 = math.sqrt(i00 * i00 + i01 * i01)
            r1 = math.sqrt(i10 * i10 + i11 * i11)
            t0 = i00 * w0 + i01 * w1
            t1 = i10 * w0 + i11 * w1
            s = min(min(t0 - tn0, tx0 - t0) / r0, min(t1 - tn1, tx1 - t1) / r1)
            inb = s >= 0.0
            if nv > 1:
                for v in range(1, nv):
                    q0 = i00 * wreq[v, 0] + i01 * wreq[v, 1]
                    q1 = i10 * wreq[v, 0] + i11 * wreq[v, 1]
                    s = min(s, min(min(q0 - tn0, tx0 - q0) / r0, min(q1 - tn1, tx1 - q1) / r1))
            margin[k] = s + 0.0  # -0.0 -> 0.0 (as the numpy engine)
            feasible[k] = 1 if s >= 0.0 else 0
            tensions[k, 0] = t0 if inb else np.nan
            tensions[k, 1] = t1 if inb else np.nan


@njit_parallel
def chunk_stats(feasible, margin, tensions, count, tpeak):
    """Feasible count and margin extremes over the feasible rows; ``tpeak`` (m) is
    raised to each cable's largest feasible tension.  Returns (count, min, max).

    Blocks of rows in parallel, then their partial results combined (count,
    min and max do not depend on the order; -0.0 is returned as 0.0)."""
    m = tensions.shape[1]
    nblocks = min(count, 64)
    if nblocks == 0:
        return 0, np.inf, -np.inf
    bsize = (count + nblocks - 1) // nblocks
    bn = np.zeros(nblocks, dtype=np.int64)
    bmin = np.full(nblocks, np.inf)
    bmax = np.full(nblocks, -np.inf)
    bt = np.full((nblocks, m), -np.inf)
    for b in nb.prange(nblocks):
        k1 = min(count, (b + 1) * bsize)
        nf = 0
        lo = np.inf
        hi = -np.inf
        for k in range(b * bsize, k1):
            if feasible[k]:
                nf += 1
                v = margin[k]
                if v < lo:
                    lo = v
                if v > hi:
                    hi = v
                for i in range(m):
                    t = tensions[k, i]
                    if t > bt[b, i]:
                        bt[b, i] = t
        bn[b] = nf
        bmin[b] = lo
        bmax[b] = hi
    nf = 0
    mmin = np.inf
    mmax = -np.inf
    for b in range(nblocks):
        nf += bn[b]
        mmin = min(mmin, bmin[b])
        mmax = max(mmax, bmax[b])
        for i in range(m):
            if bt[b, i] > tpeak[i]:
                tpeak[i] = bt[b, i]
    return nf, mmin + 0.0, mmax + 0.0


# ----------------------------------------------------------------------------
# Real hardware geometry: swivel pulleys and interference
# (conventions in cdpr_design/pulley.py and cdpr_design/interference.py)
# ----------------------------------------------------------------------------

#: Bits of the interference mask returned by :func:`interference_pose`.
HIT_CABLE_CABLE = 1
HIT_CABLE_EFFECTOR = 2
HIT_EFFECTOR_FRAME = 4
HIT_CABLE_FRAME = 8


@njit
def pulley_exit(A, i, k, eref, r, bx, by, bz, C):
    """Swivel pulley of cable i: tangent point into ``C[i]``; returns (total, free) length [m].

    ``A`` (m, 3) swivel points, ``k`` (m, 3) unit swivel axes (from the winch
    into the pulley), ``eref`` (m, 3) unit reference perpendiculars (used when
    the attachment B is on the axis), ``r`` the radius [m].  The cable wraps
    beta = pi - theta_C with theta_C = atan2(z, x) + arccos(r / D) in the
    pulley plane (cdpr_design/pulley.py; Pott 2018, pulley kinematics);
    total length r beta + |B - C|.  Returns (NaN, NaN) when B is inside the
    pulley circle.
    """
    ax, ay, az = A[i, 0], A[i, 1], A[i, 2]
    dx, dy, dz = bx - ax, by - ay, bz - az
    kx, ky, kz = k[i, 0], k[i, 1], k[i, 2]
    za = dx * kx + dy * ky + dz * kz
    rx, ry, rz = dx - za * kx, dy - za * ky, dz - za * kz
    s = math.sqrt(rx * rx + ry * ry + rz * rz)
    if r <= 0.0:
        C[i, 0], C[i, 1], C[i, 2] = ax, ay, az
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        return d, d
    if s <= 1e-12:
        ex, ey, ez = eref[i, 0], eref[i, 1], eref[i, 2]
    else:
        ex, ey, ez = rx / s, ry / s, rz / s
    x = s - r
    D = math.sqrt(x * x + za * za)
    if D < r * (1.0 - 1e-12):
        C[i, 0], C[i, 1], C[i, 2] = ax, ay, az
        return np.nan, np.nan
    theta = math.atan2(za, x) + math.acos(min(1.0, r / D))
    beta = math.pi - theta
    if beta < 0.0:
        # the attachment lies ahead along +k: the cable does not touch the pulley
        C[i, 0], C[i, 1], C[i, 2] = ax, ay, az
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        return d, d
    c, sn = math.cos(theta), math.sin(theta)
    cx = ax + r * ex + r * (c * ex + sn * kx)
    cy = ay + r * ey + r * (c * ey + sn * ky)
    cz = az + r * ez + r * (c * ez + sn * kz)
    C[i, 0], C[i, 1], C[i, 2] = cx, cy, cz
    fx, fy, fz = bx - cx, by - cy, bz - cz
    free = math.sqrt(fx * fx + fy * fy + fz * fz)
    return r * beta + free, free


@njit
def structure_matrix_pulley(px, py, pz, Rb, A, K, Eref, rad, rows, W, L, C):
    """:func:`structure_matrix` with swivel-pulley outlets.

    Fills ``W`` (n, m), total lengths ``L`` (m) [m] (arc + free segment) and
    the true outlet points ``C`` (m, 3) [m] (pulley tangent points; a_i where
    ``rad[i]`` = 0).  Column i is [u_i ; (R b_i) x u_i], u_i the unit vector
    from the attachment to C_i.  Returns False when a free segment has zero
    length or an attachment is inside a pulley circle (that column is zero).
    """
    m = A.shape[0]
    n = rows.shape[0]
    ok = True
    for i in range(m):
        bx = px + Rb[i, 0]
        by = py + Rb[i, 1]
        bz = pz + Rb[i, 2]
        li, free = pulley_exit(A, i, K, Eref, rad[i], bx, by, bz, C)
        L[i] = li
        if not (free > 1e-12):
            ok = False
            for kk in range(n):
                W[kk, i] = 0.0
            continue
        fill_column(W, i, rows, (C[i, 0] - bx) / free, (C[i, 1] - by) / free, (C[i, 2] - bz) / free,
                    Rb[i, 0], Rb[i, 1], Rb[i, 2])
    return ok


@njit
def _clamp01(v):
    return 0.0 if v < 0.0 else (1.0 if v > 1.0 else v)


@njit
def seg_seg_dist2(p0x, p0y, p0z, p1x, p1y, p1z, q0x, q0y, q0z, q1x, q1y, q1z):
    """Squared minimum distance [m^2] between segments [p0, p1] and [q0, q1].

    Closest points of two segments (Ericson, "Real-Time Collision Detection",
    2005, sec. 5.1.9): the unconstrained line-line parameters, clamped to
    [0, 1] one after the other; degenerate (point) segments handled.
    """
    d1x, d1y, d1z = p1x - p0x, p1y - p0y, p1z - p0z
    d2x, d2y, d2z = q1x - q0x, q1y - q0y, q1z - q0z
    rx, ry, rz = p0x - q0x, p0y - q0y, p0z - q0z
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    eps = 1e-300
    if a <= eps and e <= eps:
        return rx * rx + ry * ry + rz * rz
    if a <= eps:
        s = 0.0
        t = _clamp01(f / e)
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        if e <= eps:
            t = 0.0
            s = _clamp01(-c / a)
        else:
            b = d1x * d2x + d1y * d2y + d1z * d2z
            denom = a * e - b * b
            s = _clamp01((b * f - c * e) / denom) if denom > 1e-14 * a * e else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = _clamp01(-c / a)
            elif t > 1.0:
                t = 1.0
                s = _clamp01((b - c) / a)
    dx = rx + d1x * s - d2x * t
    dy = ry + d1y * s - d2y * t
    dz = rz + d1z * s - d2z * t
    return dx * dx + dy * dy + dz * dz


@njit
def _pt_seg_dist2(x, y, z, ax, ay, az, bx, by, bz):
    return seg_seg_dist2(x, y, z, x, y, z, ax, ay, az, bx, by, bz)


@njit
def cable_cable_dist(S0, S1, i, j, tol):
    """Distance [m] between the free segments of cables i and j (S0 attachments, S1 exits).

    Cables that share an endpoint (attachment or outlet within ``tol``) touch
    there by construction: for them the distance is that of the far
    endpoints to the other segment (zero only when they run along each other).
    """
    sa = (abs(S0[i, 0] - S0[j, 0]) <= tol and abs(S0[i, 1] - S0[j, 1]) <= tol
          and abs(S0[i, 2] - S0[j, 2]) <= tol)
    sb = (abs(S1[i, 0] - S1[j, 0]) <= tol and abs(S1[i, 1] - S1[j, 1]) <= tol
          and abs(S1[i, 2] - S1[j, 2]) <= tol)
    if sa or sb:
        if sa and sb:
            return 0.0
        F = S1 if sa else S0  # the far (non-shared) ends
        d1 = _pt_seg_dist2(F[i, 0], F[i, 1], F[i, 2], S0[j, 0], S0[j, 1], S0[j, 2],
                           S1[j, 0], S1[j, 1], S1[j, 2])
        d2 = _pt_seg_dist2(F[j, 0], F[j, 1], F[j, 2], S0[i, 0], S0[i, 1], S0[i, 2],
                           S1[i, 0], S1[i, 1], S1[i, 2])
        return math.sqrt(min(d1, d2))
    return math.sqrt(seg_seg_dist2(S0[i, 0], S0[i, 1], S0[i, 2], S1[i, 0], S1[i, 1], S1[i, 2],
                                   S0[j, 0], S0[j, 1], S0[j, 2], S1[j, 0], S1[j, 1], S1[j, 2]))


@njit
def segment_box_chord(s0, s1, half, dim, shrink):
    """Length [m] of the part of segment [s0, s1] inside the open box |x_k| < half_k - shrink.

    Slab clipping (Kay & Kajiya 1986) over the first ``dim`` axes; the box
    is centred at the origin (platform coordinates).  0 when they do not meet.
    """
    t0 = 0.0
    t1 = 1.0
    seg2 = 0.0
    for ax in range(dim):
        h = half[ax] - shrink
        if h <= 0.0:
            return 0.0
        a = s0[ax]
        d = s1[ax] - a
        seg2 += d * d
        if abs(d) <= 1e-300:
            if a <= -h or a >= h:
                return 0.0
            continue
        ta = (-h - a) / d
        tb = (h - a) / d
        if ta > tb:
            ta, tb = tb, ta
        if ta > t0:
            t0 = ta
        if tb < t1:
            t1 = tb
        if t0 >= t1:
            return 0.0
    for ax in range(dim, 3):
        d = s1[ax] - s0[ax]
        seg2 += d * d
    return (t1 - t0) * math.sqrt(seg2)


@njit
def cable_effector_chord(Bp, i, cp, half, dim, tol, s0, s1):
    """Length [m] of cable i's free segment inside the effector box, its own attachment excepted.

    ``Bp`` (m, 3) attachments in platform coordinates, ``cp`` (3,) the outlet
    point in platform coordinates.  An attachment inside the box (or on its
    surface within ``tol``) is first moved to the nearest face: the cable
    leaves from the surface there, and collides when it then runs through
    the box's interior (shrunk by ``tol``).  ``s0``, ``s1`` are scratch (3,).
    """
    inside = True
    best = np.inf
    bk = 0
    for ax in range(dim):
        dep = half[ax] - abs(Bp[i, ax])
        if dep < -tol:
            inside = False
        if dep < best:
            best = dep
            bk = ax
    for ax in range(3):
        s0[ax] = Bp[i, ax]
        s1[ax] = cp[ax]
    if inside:
        s0[bk] = half[bk] if Bp[i, bk] >= 0.0 else -half[bk]
    return segment_box_chord(s0, s1, half, dim, tol)


@njit
def interference_pose(S0, S1, Bp, R, px, py, pz, half, rho, flo, fhi, dim, tol, full, hits,
                      s0, s1, cp):
    """Interference at one pose; returns a bit mask (0: collision free).

    Parameters
    ----------
    S0 : (m, 3) attachment points p + R b_i in the frame [m].
    S1 : (m, 3) true outlet points (pulley tangent points or a_i) [m].
    Bp : (m, 3) attachments b_i in platform coordinates [m].
    R : (3, 3) platform rotation; (px, py, pz) platform origin [m].
    half : (3,) half extents of the effector box [m] (centred on the origin).
    rho : (m,) cable radii (diameter / 2) [m].
    flo, fhi : (3,) frame box [m].
    dim : 2 (planar: only x, y are checked) or 3.
    tol : geometric tolerance [m].
    full : when False, return at the first collision found.
    hits : (m + 2, m + 2) uint8, set to 1 for each colliding pair when
        ``full`` (index m = effector, m + 1 = frame); untouched otherwise.
    s0, s1, cp : (3,) scratch.

    Bits: HIT_CABLE_CABLE (free segments closer than the sum of the cable
    radii, touching included), HIT_CABLE_EFFECTOR (a free segment through
    the effector box other than at its own attachment), HIT_EFFECTOR_FRAME
    (an effector box corner outside the frame box), HIT_CABLE_FRAME (an
    attachment point outside the frame box: the free cable leaves the frame).
    """
    m = S0.shape[0]
    mask = 0
    # effector - frame: every box corner inside the frame box
    ncorner = 4 if dim == 2 else 8
    for c in range(ncorner):
        sx = half[0] if (c & 1) else -half[0]
        sy = half[1] if (c & 2) else -half[1]
        sz = half[2] if (c & 4) else -half[2]
        if dim == 2:
            sz = 0.0
        vx = px + R[0, 0] * sx + R[0, 1] * sy + R[0, 2] * sz
        vy = py + R[1, 0] * sx + R[1, 1] * sy + R[1, 2] * sz
        vz = pz + R[2, 0] * sx + R[2, 1] * sy + R[2, 2] * sz
        out = vx < flo[0] - tol or vx > fhi[0] + tol or vy < flo[1] - tol or vy > fhi[1] + tol
        if dim == 3:
            out = out or vz < flo[2] - tol or vz > fhi[2] + tol
        if out:
            mask |= HIT_EFFECTOR_FRAME
            if full:
                hits[m, m + 1] = 1
                hits[m + 1, m] = 1
            else:
                return mask
            break
    for i in range(m):
        # cable - frame: the attachment point (the free segment's end) outside the frame
        out = (S0[i, 0] < flo[0] - tol or S0[i, 0] > fhi[0] + tol
               or S0[i, 1] < flo[1] - tol or S0[i, 1] > fhi[1] + tol)
        if dim == 3:
            out = out or S0[i, 2] < flo[2] - tol or S0[i, 2] > fhi[2] + tol
        if out:
            mask |= HIT_CABLE_FRAME
            if not full:
                return mask
            hits[i, m + 1] = 1
            hits[m + 1, i] = 1
        # cable - effector, in platform coordinates: cp = R^T (C_i - p)
        dx, dy, dz = S1[i, 0] - px, S1[i, 1] - py, S1[i, 2] - pz
        for r in range(3):
            cp[r] = R[0, r] * dx + R[1, r] * dy + R[2, r] * dz
        if cable_effector_chord(Bp, i, cp, half, dim, tol, s0, s1) > tol:
            mask |= HIT_CABLE_EFFECTOR
            if not full:
                return mask
            hits[i, m] = 1
            hits[m, i] = 1
    for i in range(m):
        for j in range(i + 1, m):
            if cable_cable_dist(S0, S1, i, j, tol) <= rho[i] + rho[j] + tol:
                mask |= HIT_CABLE_CABLE
                if not full:
                    return mask
                hits[i, j] = 1
                hits[j, i] = 1
    return mask


@njit_parallel
def sweep_points(P, Rb, R, A, K, Eref, rad, rows, wreq, tmin, tmax, combos, kind,
                 check, Bp, half, rho, flo, fhi, dim, tol, full,
                 feasible, margin, tensions, lengths, cmask):
    """Evaluate explicit positions ``P`` (count, 3) at one orientation, pulley- and interference-aware.

    Same outputs as :func:`sweep_grid` for rows 0..count-1 (statics only:
    ``feasible`` does not include interference), plus ``cmask`` (uint8): the
    :func:`interference_pose` bits when ``check`` (0 when not checked).
    Outlets with ``rad[i]`` > 0 are swivel pulleys (:func:`structure_matrix_pulley`).
    """
    count = P.shape[0]
    n = rows.shape[0]
    m = A.shape[0]
    nblocks = min(count, 256)
    if nblocks == 0:
        return
    bsize = (count + nblocks - 1) // nblocks
    for b in nb.prange(nblocks):
        W = np.empty((n, m))
        t = np.empty(m)
        L = np.empty(m)
        C = np.empty((m, 3))
        S0 = np.empty((m, 3))
        hits = np.zeros((m + 2, m + 2), dtype=np.uint8)
        s0 = np.empty(3)
        s1 = np.empty(3)
        cp = np.empty(3)
        k0 = b * bsize
        k1 = min(count, k0 + bsize)
        for k in range(k0, k1):
            px, py, pz = P[k, 0], P[k, 1], P[k, 2]
            ok = structure_matrix_pulley(px, py, pz, Rb, A, K, Eref, rad, rows, W, L, C)
            for i in range(m):
                lengths[k, i] = L[i]
            if check:
                for i in range(m):
                    S0[i, 0] = px + Rb[i, 0]
                    S0[i, 1] = py + Rb[i, 1]
                    S0[i, 2] = pz + Rb[i, 2]
                cmask[k] = interference_pose(S0, C, Bp, R, px, py, pz, half, rho, flo, fhi, dim,
                                             tol, full, hits, s0, s1, cp)
            else:
                cmask[k] = 0
            if not ok:
                feasible[k] = 0
                margin[k] = np.nan
                for i in range(m):
                    tensions[k, i] = np.nan
                continue
            f, mg = eval_pose(W, wreq, tmin, tmax, combos, kind, t)
            feasible[k] = 1 if f else 0
            margin[k] = mg + 0.0  # -0.0 -> 0.0: one zero in the CSV, whatever the engine
            for i in range(m):
                tensions[k, i] = t[i]
