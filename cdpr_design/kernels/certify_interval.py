"""The interval pieces of the certified tests (:mod:`cdpr_design.kernels.certify`): the structure
matrix over a box of positions and geometries, its derivatives in the position, a facet's support
gap, and Krawczyk's enclosure of the solutions of an interval linear system.

The structure matrix's column i is [u_i ; (R b_i) x u_i] with u_i = d_i / |d_i|,
d_i = A_i - R b_i - p; each component of u_i is enclosed exactly for independent component
intervals of d_i (:func:`~cdpr_design.kernels.interval.unit_component`), the moment rows by the
interval cross product.  Krawczyk's operator with a midpoint-inverse preconditioner Y (Krawczyk
1969; Neumaier, "Interval Methods for Systems of Equations", 1990, sec. 4.1): with C = I - Y [A]
and z = Y([b] - [A] x~), ||C||_inf <= beta < 1 proves every A in [A] regular and puts every
solution within ||z||_inf / (1 - beta) of x~.  Every operation rounds outward
(:mod:`cdpr_design.kernels.interval`).
"""

from __future__ import annotations

import numpy as np

from cdpr_design.kernels._jit import njit
from cdpr_design.kernels.interval import down, iabs, iadd, idiv, imul, iscale, isqr, isqrt, isub, unit_component, up
from cdpr_design.kernels.linalg import inverse_into

#: Krawczyk refinements after the first enclosure
KRAWCZYK_STEPS = 2


@njit
def interval_units(plo, phi, Alo, Ahi, Blo, Bhi, U, L):
    """Enclose the cables' unit vectors u_i over the position box [plo, phi] (3,) [m], outlets
    in [Alo, Ahi] and rotated attachments in [Blo, Bhi] (m, 3) [m]: ``U`` (m, 3, 2) (lower,
    upper) and the lengths ``L`` (m, 2) [m].

    Returns True when every cable's length is proven positive over the box (else its
    direction is undefined somewhere: its components are [-1, 1])."""
    ok = True
    for i in range(Alo.shape[0]):
        # d = A - Rb - p, one interval per component
        d0l, d0h = isub(Alo[i, 0], Ahi[i, 0], Blo[i, 0], Bhi[i, 0])
        d0l, d0h = isub(d0l, d0h, plo[0], phi[0])
        d1l, d1h = isub(Alo[i, 1], Ahi[i, 1], Blo[i, 1], Bhi[i, 1])
        d1l, d1h = isub(d1l, d1h, plo[1], phi[1])
        d2l, d2h = isub(Alo[i, 2], Ahi[i, 2], Blo[i, 2], Bhi[i, 2])
        d2l, d2h = isub(d2l, d2h, plo[2], phi[2])
        s0l, s0h = isqr(d0l, d0h)
        s1l, s1h = isqr(d1l, d1h)
        s2l, s2h = isqr(d2l, d2h)
        r0l, r0h = iadd(s1l, s1h, s2l, s2h)
        r1l, r1h = iadd(s0l, s0h, s2l, s2h)
        r2l, r2h = iadd(s0l, s0h, s1l, s1h)
        ll, lh = iadd(r0l, r0h, s0l, s0h)
        if not (ll > 0.0):
            ok = False
        L[i, 0], L[i, 1] = isqrt(ll, lh)
        U[i, 0, 0], U[i, 0, 1] = unit_component(d0l, d0h, r0l, r0h)
        U[i, 1, 0], U[i, 1, 1] = unit_component(d1l, d1h, r1l, r1h)
        U[i, 2, 0], U[i, 2, 1] = unit_component(d2l, d2h, r2l, r2h)
    return ok


@njit
def column_rows(V, i, Blo, Bhi, rows, Wl, Wh):
    """Column i of [Wl, Wh] (n, m): [v ; (R b_i) x v] restricted to ``rows``, for the interval
    3-vector ``V`` (3, 2) and cable i's rotated attachment box (the structure matrix's column
    for v = u_i, its derivative along a position axis for v = du_i/dp)."""
    bxl = Blo[i, 0]
    bxh = Bhi[i, 0]
    byl = Blo[i, 1]
    byh = Bhi[i, 1]
    bzl = Blo[i, 2]
    bzh = Bhi[i, 2]
    for k in range(rows.shape[0]):
        r = rows[k]
        if r < 3:
            lo, hi = V[r, 0], V[r, 1]
        elif r == 3:  # by vz - bz vy
            al, ah = imul(byl, byh, V[2, 0], V[2, 1])
            bl, bh = imul(bzl, bzh, V[1, 0], V[1, 1])
            lo, hi = isub(al, ah, bl, bh)
        elif r == 4:  # bz vx - bx vz
            al, ah = imul(bzl, bzh, V[0, 0], V[0, 1])
            bl, bh = imul(bxl, bxh, V[2, 0], V[2, 1])
            lo, hi = isub(al, ah, bl, bh)
        else:  # bx vy - by vx
            al, ah = imul(bxl, bxh, V[1, 0], V[1, 1])
            bl, bh = imul(byl, byh, V[0, 0], V[0, 1])
            lo, hi = isub(al, ah, bl, bh)
        Wl[k, i] = lo
        Wh[k, i] = hi


@njit
def interval_structure(plo, phi, Alo, Ahi, Blo, Bhi, rows, Wl, Wh, U, L):
    """Enclose the structure matrix over the box (:func:`interval_units`): ``Wl``, ``Wh``
    (n, m); ``U``, ``L`` receive the unit vectors and lengths.  Returns :func:`interval_units`'s flag."""
    ok = interval_units(plo, phi, Alo, Ahi, Blo, Bhi, U, L)
    for i in range(Alo.shape[0]):
        column_rows(U[i], i, Blo, Bhi, rows, Wl, Wh)
    return ok


@njit
def structure_derivative(axis, U, L, Blo, Bhi, rows, Dl, Dh, V):
    """Enclose dW/dp_axis over the box into [Dl, Dh] (n, m): du_i/dp_k = -(e_k - u_i u_ik) / L_i
    (u_i = (A_i - R b_i - p) / L_i), through :func:`column_rows`; ``V`` (3, 2) is scratch."""
    for i in range(U.shape[0]):
        for c in range(3):
            if c == axis:
                pl, ph = isqr(U[i, c, 0], U[i, c, 1])
                pl, ph = isub(1.0, 1.0, pl, ph)
            else:
                pl, ph = imul(U[i, c, 0], U[i, c, 1], U[i, axis, 0], U[i, axis, 1])
                pl, ph = -ph, -pl
            V[c, 0], V[c, 1] = idiv(-ph, -pl, L[i, 0], L[i, 1])
        column_rows(V, i, Blo, Bhi, rows, Dl, Dh)


@njit
def half_ranges(tmin, tmax, tmid, rho):
    """``tmid`` = the bounds' midpoints (floats) and ``rho`` >= max |t - tmid| over the bounds, rounded up."""
    for j in range(tmin.shape[0]):
        tmid[j] = 0.5 * (tmin[j] + tmax[j])
        a = up(tmid[j] - tmin[j])
        b = up(tmax[j] - tmid[j])
        rho[j] = max(a, b)


@njit
def support_gap(nu, Wl, Wh, tmid, rho, w):
    """The interval of s = sum_j rho_j |nu . w_j| - |nu . (W t_mid - w)| over the interval
    structure matrix [Wl, Wh] (n, m), for the float direction ``nu`` (n,) and wrench ``w`` (n,)."""
    n, m = Wl.shape
    sl = 0.0
    sh = 0.0
    cl = 0.0
    ch = 0.0
    for j in range(m):
        ll = 0.0
        lh = 0.0
        for i in range(n):
            pl, ph = iscale(nu[i], Wl[i, j], Wh[i, j])
            ll, lh = iadd(ll, lh, pl, ph)
        al, ah = iabs(ll, lh)
        pl, ph = iscale(rho[j], al, ah)
        sl, sh = iadd(sl, sh, pl, ph)
        pl, ph = iscale(tmid[j], ll, lh)
        cl, ch = iadd(cl, ch, pl, ph)
    for i in range(n):
        pl, ph = iscale(nu[i], w[i], w[i])
        cl, ch = isub(cl, ch, pl, ph)
    al, ah = iabs(cl, ch)
    return isub(sl, sh, al, ah)


@njit
def preconditioner(Al, Ah, Am, Y, Cl, Ch, work):
    """The midpoint inverse ``Y`` of [Al, Ah] (n, n) (midpoint into ``Am``), C = I - Y [A] into
    [Cl, Ch] (n, n), and beta >= ||C||_inf rounded up (returned; inf when the midpoint is
    singular).  ``work`` (n, >= 2n) is scratch."""
    n = Al.shape[0]
    for i in range(n):
        for j in range(n):
            Am[i, j] = 0.5 * (Al[i, j] + Ah[i, j])
    if not inverse_into(Am, Y, work):
        return np.inf
    beta = 0.0
    for i in range(n):
        row = 0.0
        for j in range(n):
            cl = 1.0 if i == j else 0.0
            ch = cl
            for k in range(n):
                pl, ph = iscale(Y[i, k], Al[k, j], Ah[k, j])
                cl, ch = isub(cl, ch, pl, ph)
            Cl[i, j] = cl
            Ch[i, j] = ch
            row = up(row + max(-cl, ch))
        beta = max(beta, row)
    return beta


@njit
def krawczyk_box(xt, zl, zh, Cl, Ch, beta, Xl, Xh, work):
    """Enclose into [Xl, Xh] (n,) every x with x = xt + z + C (x - xt) for some z in [zl, zh] and C
    in [Cl, Ch] (n, n), ||C||_inf <= ``beta``: within r = ||z||_inf / (1 - beta) of the float point
    ``xt`` (n,), refined :data:`KRAWCZYK_STEPS` times by xt + z + C (X - xt).  False when beta is
    not below 1.  ``work`` (n, >= 2) is scratch."""
    n = xt.shape[0]
    if not (beta < 1.0):
        return False
    delta = 0.0
    for i in range(n):
        delta = max(delta, max(-zl[i], zh[i]))
    r = up(delta / down(1.0 - beta))
    for i in range(n):
        Xl[i] = down(xt[i] - r)
        Xh[i] = up(xt[i] + r)
    for _ in range(KRAWCZYK_STEPS):
        for i in range(n):
            kl, kh = iadd(xt[i], xt[i], zl[i], zh[i])
            for j in range(n):
                dl, dh = isub(Xl[j], Xh[j], xt[j], xt[j])
                pl, ph = imul(Cl[i, j], Ch[i, j], dl, dh)
                kl, kh = iadd(kl, kh, pl, ph)
            work[i, 0] = max(kl, Xl[i])
            work[i, 1] = min(kh, Xh[i])
        for i in range(n):
            Xl[i] = work[i, 0]
            Xh[i] = work[i, 1]
    return True


@njit
def krawczyk(Al, Ah, bl, bh, Am, Y, xt, Cl, Ch, zl, zh, Xl, Xh, work):
    """Enclose the solutions of A x = b for every A in [Al, Ah] (n, n) and b in [bl, bh] (n,)
    into [Xl, Xh] (n,).  Returns False when regularity is not proven (then X is meaningless).

    ``Am``, ``Y``, ``Cl``, ``Ch`` (n, n), ``xt``, ``zl``, ``zh`` (n,) and ``work`` (n, >= 2n)
    are scratch (:func:`preconditioner`, then :func:`krawczyk_box` with z = Y ([b] - [A] xt),
    xt = Y mid(b))."""
    n = Al.shape[0]
    beta = preconditioner(Al, Ah, Am, Y, Cl, Ch, work)
    if not (beta < 1.0):
        return False
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += Y[i, j] * 0.5 * (bl[j] + bh[j])
        xt[i] = s
    # z = Y (b - A xt)
    for i in range(n):
        zl[i] = 0.0
        zh[i] = 0.0
    for k in range(n):
        rl, rh = bl[k], bh[k]
        for j in range(n):
            pl, ph = iscale(xt[j], Al[k, j], Ah[k, j])
            rl, rh = isub(rl, rh, pl, ph)
        for i in range(n):
            pl, ph = iscale(Y[i, k], rl, rh)
            zl[i], zh[i] = iadd(zl[i], zh[i], pl, ph)
    return krawczyk_box(xt, zl, zh, Cl, Ch, beta, Xl, Xh, work)
