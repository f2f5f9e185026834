"""Interval tests of a box of positions: every pose feasible (``inside``), none (``outside``), or
neither proven (``undecided``).

A box of platform positions X at one fixed orientation, with outlets A_i and
rotated attachments R b_i each in a box of its own (geometric tolerances;
points when there are none).  Everything that decides is computed with the
outward-rounded interval operations of :mod:`cdpr_design.kernels.interval`;
floating-point values at the box's centre only *choose* what to test (a
facet normal, a basis of cables, the tensions of the other cables), and any
choice gives a valid proof.

Structure matrix over the box.  Column i is [u_i ; (R b_i) x u_i] with
u_i = d_i / |d_i|, d_i = A_i - R b_i - p.  Each component of u_i is enclosed
exactly for independent component intervals of d_i
(:func:`~cdpr_design.kernels.interval.unit_component`: it is monotonic in
that component and in the sum of the others' squares); the moment rows are
the interval cross product.

``outside``.  For any direction nu and any feasible wrench w = W t,
t in [t_min, t_max]: |nu . (w - W t_mid)| <= sum_j |nu . w_j| rho_j with
rho_j = max |t_j - t_mid,j| (the support function of the zonotope of
available wrenches: hyperplane shifting, Gouttefarde, Daney & Merlet, IEEE
T-RO 27(1) 2011; Bouchard, Gosselin & Moore 2010).  So if, for one required
wrench vertex and one nu, the interval of

    s(X) = sum_j rho_j |nu . w_j(X)| - |nu . (W(X) t_mid - w)|

lies below 0 (below mu |nu| for a capacity margin mu), no pose of X is
feasible.  nu is the unit normal of the facet most violated at the centre,
fixed over the box (so it carries no dependency).  The centre decides which
proof is tried: outside when it is infeasible, inside when it is feasible.

``inside``.  Find tensions t_c at the centre that balance it with room to
spare (the ones nearest t_mid within the bounds shrunk by a fraction, by the
exact minimum-norm QP, bisecting on the fraction), pick n cables B whose columns are best conditioned
at the centre (largest |det| times their least slack in t_c), and fix the
others F at t_c.  If,
for every pose of X (and every geometry within tolerance, every wrench
vertex), W_B t_B = w - W_F t_F + e (e in [-mu, mu]^n, which holds the ball of
radius mu) has its solution in the bounds, every pose is feasible with those
tensions and margin >= mu.  The solutions over the box are enclosed by the
Krawczyk operator with a midpoint-inverse preconditioner Y (Krawczyk 1969;
Neumaier, "Interval Methods for Systems of Equations", 1990, sec. 4.1): with
C = I - Y [A] and z = Y([b] - [A] x~), ||C||_inf <= beta < 1 proves every
A in [A] regular and puts every solution within
r = ||z||_inf / (1 - beta) of x~, and x~ + z + C (X0 - x~) refines that box.
For m = n this is the enclosure of t = W^-1 w of the square case.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.kernels._jit import njit
from cdpr_design.kernels.geometry import structure_matrix
from cdpr_design.kernels.hsm import facet_normal
from cdpr_design.kernels.interval import down, iabs, iadd, idiv, imul, iscale, isqr, isqrt, isub, unit_component, up
from cdpr_design.kernels.hsm import make_scratch as make_qp_scratch
from cdpr_design.kernels.linalg import det_in_place, inverse_into
from cdpr_design.kernels.tension_qp import min_norm_tensions

#: box statuses (``cdpr_design.workspaces.certify`` names them)
INSIDE = 1
OUTSIDE = -1
UNDECIDED = 0

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
def krawczyk(Al, Ah, bl, bh, Am, Y, xt, Cl, Ch, zl, zh, Xl, Xh, work):
    """Enclose the solutions of A x = b for every A in [Al, Ah] (n, n) and b in [bl, bh] (n,)
    into [Xl, Xh] (n,).  Returns False when regularity is not proven (then X is meaningless).

    ``Am``, ``Y``, ``Cl``, ``Ch`` (n, n), ``xt``, ``zl``, ``zh`` (n,) and ``work`` (n, >= 2n)
    are scratch."""
    n = Al.shape[0]
    for i in range(n):
        for j in range(n):
            Am[i, j] = 0.5 * (Al[i, j] + Ah[i, j])
    if not inverse_into(Am, Y, work):
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
    # C = I - Y A and beta = ||C||_inf (rounded up)
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
def best_basis(Wc, bases, slack, work):
    """The row of ``bases`` (C(m, n), n) whose columns of the float matrix ``Wc`` score best:
    |det| times the least relative slack ``slack`` (m,) of its cables (-1 if none scores)."""
    n = Wc.shape[0]
    best = 0.0
    arg = -1
    for c in range(bases.shape[0]):
        low = np.inf
        for j in range(n):
            low = min(low, slack[bases[c, j]])
        if not (low > 0.0):
            continue
        for i in range(n):
            for j in range(n):
                work[i, j] = Wc[i, bases[c, j]]
        d = abs(det_in_place(work, n)) * low
        if d > best:
            best = d
            arg = c
    return arg


#: bisection steps on the shrinkage of the bounds for the centre's tensions
SHRINK_STEPS = 6


@njit
def shrunk_qp(Wc, rhs, tmin, tmax, tmid, f, lo, hi, s, scr):
    """The tensions - tmid nearest 0 within the bounds shrunk by ``f`` (t_max - t_min) each side."""
    for j in range(Wc.shape[1]):
        g = f * (tmax[j] - tmin[j])
        lo[j] = tmin[j] - tmid[j] + g
        hi[j] = tmax[j] - tmid[j] - g
    return min_norm_tensions(Wc, rhs, lo, hi, s, scr)


@njit
def centre_tensions(Wc, w, tmin, tmax, tmid, t, lo, hi, rhs, s, scr):
    """Feasible tensions t (m,) [N] at the centre with room to spare: the ones nearest ``tmid``
    within the bounds shrunk by nearly the largest fraction that admits any (a bisection of
    :data:`SHRINK_STEPS` steps over the exact minimum-norm QP of
    :mod:`cdpr_design.kernels.tension_qp`, in t - tmid): close to the tensions whose least
    relative slack is largest.  False when even the full bounds admit none (the centre is
    infeasible)."""
    n, m = Wc.shape
    if m == n:  # square: the tensions are unique, t = Wc^-1 w (scr[1] is n x n, scr[0] n x 2n)
        if not inverse_into(Wc, scr[1], scr[0]):
            return False
        ok = True
        for j in range(m):
            tj = 0.0
            for i in range(n):
                tj += scr[1][j, i] * w[i]
            t[j] = tj
            ok = ok and tmin[j] <= tj <= tmax[j]
        return ok
    for i in range(n):
        r = w[i]
        for j in range(m):
            r -= Wc[i, j] * tmid[j]
        rhs[i] = r
    if not shrunk_qp(Wc, rhs, tmin, tmax, tmid, 0.0, lo, hi, s, scr):
        return False
    for j in range(m):
        t[j] = tmid[j] + s[j]
    a = 0.0
    b = 0.5
    for _ in range(SHRINK_STEPS):
        f = 0.5 * (a + b)
        if shrunk_qp(Wc, rhs, tmin, tmax, tmid, f, lo, hi, s, scr):
            a = f
            for j in range(m):
                t[j] = tmid[j] + s[j]
        else:
            b = f
    return True


@njit
def outside_test(plo, phi, pc, Alo, Ahi, Blo, Bhi, rows, Wc, wv, tmid, rho, mu, facets, nu, best_nu, box):
    """Whether the box is proven outside: for some wrench vertex, the facet most violated at
    the centre has its support gap below ``mu`` |nu| over the whole box (natural interval
    extension, then the centred form of :func:`centred_gap`)."""
    n, m = Wc.shape
    Wl, Wh = box[0], box[1]
    for k in range(wv.shape[0]):
        worst = np.inf
        for c in range(facets.shape[0]):
            if not facet_normal(Wc, facets[c], nu):
                continue
            half = 0.0
            gap = 0.0
            for j in range(m):
                lj = 0.0
                for i in range(n):
                    lj += nu[i] * Wc[i, j]
                half += abs(lj) * rho[j]
                gap += lj * tmid[j]
            for i in range(n):
                gap -= nu[i] * wv[k, i]
            s = half - abs(gap)
            if s < worst:
                worst = s
                for i in range(n):
                    best_nu[i] = nu[i]
        if not (worst < mu):
            continue
        ql, qh = 0.0, 0.0
        for i in range(n):
            pl, ph = isqr(best_nu[i], best_nu[i])
            ql, qh = iadd(ql, qh, pl, ph)
        nl, nh = isqrt(ql, qh)
        ml, mh = iscale(mu, nl, nh)
        sl, sh = support_gap(best_nu, Wl, Wh, tmid, rho, wv[k])
        if sh < ml:
            return True
        sh = centred_gap(plo, phi, pc, Alo, Ahi, Blo, Bhi, rows, best_nu, tmid, rho, wv[k], box)
        if sh < ml:
            return True
    return False


@njit
def centred_gap(plo, phi, pc, Alo, Ahi, Blo, Bhi, rows, nu, tmid, rho, w, box):
    """An upper bound over the box of the support gap s (:func:`support_gap`) by centred forms.

    Where the sign sigma_j of l_j = nu . w_j is proven constant over the box (natural
    extension), and the sign sigma_g of the gap g = nu . (W t_mid - w) is, the part
    F = sum_j rho_j sigma_j l_j - sigma_g g of s is smooth and lies in
    F(c) + sum_k dF/dp_k (X) (X_k - c_k), dF/dp_k = sum_j (rho_j sigma_j - sigma_g t_mid,j)
    nu . dw_j/dp_k; each l_j of unknown sign (the facet's own cables, 0 at the centre) adds
    rho_j max |l_j(c) + sum_k nu . dw_j/dp_k (X) (X_k - c_k)|.  ``inf`` when the gap's sign is
    not proven."""
    (Wl, Wh, U, L, Wcl, Wch, Uc, Lc, Dl, Dh, V, Al, Ah, Acl, Ach, bl, bh, Xl, Xh, Tl, Th, gl, gh, yl, yh) = box
    n, m = Wl.shape
    sig = np.empty(m)
    El = np.empty(m)
    Eh = np.empty(m)
    cl, ch = 0.0, 0.0
    for j in range(m):
        ll, lh = 0.0, 0.0
        for i in range(n):
            pl, ph = iscale(nu[i], Wl[i, j], Wh[i, j])
            ll, lh = iadd(ll, lh, pl, ph)
        sig[j] = 1.0 if ll > 0.0 else (-1.0 if lh < 0.0 else 0.0)
        pl, ph = iscale(tmid[j], ll, lh)
        cl, ch = iadd(cl, ch, pl, ph)
    for i in range(n):
        pl, ph = iscale(nu[i], w[i], w[i])
        cl, ch = isub(cl, ch, pl, ph)
    if cl > 0.0:
        sg = 1.0
    elif ch < 0.0:
        sg = -1.0
    else:
        return np.inf
    # F(c) and the l_j(c), from the structure matrix enclosed at the centre point
    interval_structure(pc, pc, Alo, Ahi, Blo, Bhi, rows, Wcl, Wch, Uc, Lc)
    fl, fh = iscale(sg, 0.0, 0.0)
    for i in range(n):
        pl, ph = iscale(sg * nu[i], w[i], w[i])
        fl, fh = iadd(fl, fh, pl, ph)
    for j in range(m):
        ll, lh = 0.0, 0.0
        for i in range(n):
            pl, ph = iscale(nu[i], Wcl[i, j], Wch[i, j])
            ll, lh = iadd(ll, lh, pl, ph)
        El[j], Eh[j] = ll, lh
        kl, kh = isub(rho[j] * sig[j], rho[j] * sig[j], sg * tmid[j], sg * tmid[j])
        pl, ph = imul(kl, kh, ll, lh)
        fl, fh = iadd(fl, fh, pl, ph)
    for axis in range(3):
        if not (phi[axis] > plo[axis]):
            continue
        structure_derivative(axis, U, L, Blo, Bhi, rows, Dl, Dh, V)
        xl, xh = isub(plo[axis], phi[axis], pc[axis], pc[axis])
        for j in range(m):
            dl, dh = 0.0, 0.0
            for i in range(n):
                pl, ph = iscale(nu[i], Dl[i, j], Dh[i, j])
                dl, dh = iadd(dl, dh, pl, ph)
            dl, dh = imul(dl, dh, xl, xh)
            kl, kh = isub(rho[j] * sig[j], rho[j] * sig[j], sg * tmid[j], sg * tmid[j])
            pl, ph = imul(kl, kh, dl, dh)
            fl, fh = iadd(fl, fh, pl, ph)
            if sig[j] == 0.0:
                El[j], Eh[j] = iadd(El[j], Eh[j], dl, dh)
    for j in range(m):
        if sig[j] == 0.0:
            pl, ph = iscale(rho[j], 0.0, max(-El[j], Eh[j]))
            fl, fh = iadd(fl, fh, pl, ph)
    return fh


@njit
def make_scratch(n, m):
    """The work arrays of :func:`classify_box` (one set per block of boxes): a tuple of the
    centre's floats, one of the box's enclosures and one of the Krawczyk steps."""
    centre = (np.empty((n, m)), np.empty(m), np.empty(m), np.empty(m), np.empty(n), np.empty(n), np.empty(m),
              np.empty(m), np.empty(m), np.empty(m), np.empty(n), np.empty(m), make_qp_scratch(n, m, 1))
    box = (np.empty((n, m)), np.empty((n, m)), np.empty((m, 3, 2)), np.empty((m, 2)), np.empty((n, m)),
           np.empty((n, m)), np.empty((m, 3, 2)), np.empty((m, 2)), np.empty((n, m)), np.empty((n, m)),
           np.empty((3, 2)), np.empty((n, n)), np.empty((n, n)), np.empty((n, n)), np.empty((n, n)), np.empty(n),
           np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
           np.empty(n), np.empty(n))
    kr = (np.empty((n, n)), np.empty((n, n)), np.empty(n), np.empty((n, n)), np.empty((n, n)), np.empty(n),
          np.empty(n), np.empty((n, max(2 * n, 2))))
    return centre, box, kr


@njit
def basis_enclosure(Wl, Wh, bases, basis, t, tmin, tmax, w, mu, Al, Ah, bl, bh, kr, Xl, Xh):
    """Enclose into [Xl, Xh] (n,) the tensions of the basis cables ``bases[basis]`` that balance
    every wrench of w + [-mu, mu]^n (n,) for every structure matrix in [Wl, Wh] (n, m), the other
    cables held at ``t`` clipped to their bounds.  ``Al``, ``Ah`` receive the basis columns;
    ``kr``: the Krawczyk scratch.  False when regularity is not proven."""
    n, m = Wl.shape
    for i in range(n):
        for j in range(n):
            Al[i, j] = Wl[i, bases[basis, j]]
            Ah[i, j] = Wh[i, bases[basis, j]]
        bl[i], bh[i] = iadd(w[i], w[i], -mu, mu)
    for j in range(m):
        if in_basis(bases, basis, j) >= 0:
            continue
        tj = min(max(t[j], tmin[j]), tmax[j])
        for i in range(n):
            pl, ph = iscale(tj, Wl[i, j], Wh[i, j])
            bl[i], bh[i] = isub(bl[i], bh[i], pl, ph)
    Am, Y, xt, Cl, Ch, zl, zh, work = kr
    return krawczyk(Al, Ah, bl, bh, Am, Y, xt, Cl, Ch, zl, zh, Xl, Xh, work)


@njit
def in_basis(bases, basis, j):
    """The slot of cable j in ``bases[basis]`` (-1 if it is not there)."""
    for q in range(bases.shape[1]):
        if bases[basis, q] == j:
            return q
    return -1


@njit
def within(bases, basis, Xl, Xh, tmin, tmax):
    """Whether the enclosure [Xl, Xh] of the basis tensions lies within their bounds."""
    for q in range(bases.shape[1]):
        c = bases[basis, q]
        if not (Xl[q] >= tmin[c] and Xh[q] <= tmax[c]):
            return False
    return True


@njit
def mean_value(plo, phi, pc, Alo, Ahi, Blo, Bhi, rows, bases, basis, t, tmin, tmax, w, mu, box, kr):
    """Refine the first-order enclosure of the basis tensions (``box`` [15], [16]) by the centred
    (mean-value) form t_B(X) in t_B(c) + sum_k dt_B/dp_k (X) (X_k - c_k), with
    dt_B/dp_k = -W_B^-1 sum_j (dW_j/dp_k) t_j enclosed by Krawczyk over the box; the result
    is intersected into ``box`` [15], [16].  False when a step is not proven."""
    (Wl, Wh, U, L, Wcl, Wch, Uc, Lc, Dl, Dh, V, Al, Ah, Acl, Ach, bl, bh, Xl, Xh, Tl, Th, gl, gh, yl, yh) = box
    n = rows.shape[0]
    interval_structure(pc, pc, Alo, Ahi, Blo, Bhi, rows, Wcl, Wch, Uc, Lc)
    if not basis_enclosure(Wcl, Wch, bases, basis, t, tmin, tmax, w, mu, Acl, Ach, bl, bh, kr, Tl, Th):
        return False
    Am, Y, xt, Cl, Ch, zl, zh, work = kr
    for axis in range(3):
        if not (phi[axis] > plo[axis]):
            continue
        structure_derivative(axis, U, L, Blo, Bhi, rows, Dl, Dh, V)
        for i in range(n):
            gl[i] = 0.0
            gh[i] = 0.0
            for j in range(Wl.shape[1]):
                q = in_basis(bases, basis, j)
                if q >= 0:
                    pl, ph = imul(Dl[i, j], Dh[i, j], Xl[q], Xh[q])
                else:
                    pl, ph = iscale(min(max(t[j], tmin[j]), tmax[j]), Dl[i, j], Dh[i, j])
                gl[i], gh[i] = iadd(gl[i], gh[i], pl, ph)
        if not krawczyk(Al, Ah, gl, gh, Am, Y, xt, Cl, Ch, zl, zh, yl, yh, work):
            return False
        dl, dh = isub(plo[axis], phi[axis], pc[axis], pc[axis])
        for q in range(n):
            pl, ph = imul(-yh[q], -yl[q], dl, dh)
            Tl[q], Th[q] = iadd(Tl[q], Th[q], pl, ph)
    for q in range(n):
        Xl[q] = max(Xl[q], Tl[q])
        Xh[q] = min(Xh[q], Th[q])
    return True


@njit
def square_outside(plo, phi, pc, Alo, Ahi, Blo, Bhi, rows, bases, t, tmin, tmax, w, box, kr):
    """Square case (m = n): whether the unique tensions t = W^-1 w, enclosed over the box by
    Krawczyk (first order, then the centred form), have a component wholly outside its bounds
    at every pose of the box (which also proves W regular there)."""
    Wl, Wh, Al, Ah, bl, bh, Xl, Xh = box[0], box[1], box[11], box[12], box[15], box[16], box[17], box[18]
    if not basis_enclosure(Wl, Wh, bases, 0, t, tmin, tmax, w, 0.0, Al, Ah, bl, bh, kr, Xl, Xh):
        return False
    if not beyond(bases, Xl, Xh, tmin, tmax):
        mean_value(plo, phi, pc, Alo, Ahi, Blo, Bhi, rows, bases, 0, t, tmin, tmax, w, 0.0, box, kr)
    return beyond(bases, Xl, Xh, tmin, tmax)


@njit
def beyond(bases, Xl, Xh, tmin, tmax):
    """Whether some component of the enclosure [Xl, Xh] of the tensions of ``bases[0]`` lies
    wholly below its lower bound or above its upper one."""
    for q in range(bases.shape[1]):
        c = bases[0, q]
        if Xh[q] < tmin[c] or Xl[q] > tmax[c]:
            return True
    return False


@njit
def classify_box(plo, phi, pc, Alo, Ahi, Blo, Bhi, Ac, Bc, rows, wv, tmin, tmax, mu, facets, bases, scr):
    """The status of one box of positions [plo, phi] (3,) [m] with centre ``pc``: INSIDE,
    OUTSIDE or UNDECIDED (module docstring).  ``Ac``, ``Bc`` (m, 3): the nominal outlets and
    rotated attachments; ``wv`` (nv, n): the required-wrench vertices; ``mu`` [N]: the capacity
    margin asked (0 for feasibility); ``facets`` (C(m, n-1), n-1) and ``bases`` (C(m, n), n):
    the cable subsets; ``scr`` from :func:`make_scratch`."""
    m = Alo.shape[0]
    n = rows.shape[0]
    centre, box, kr = scr
    (Wc, L, tmid, rho, nu, best_nu, t, lo, hi, s, rhs, slack, qp) = centre
    (Wl, Wh, U, Lx, Wcl, Wch, Uc, Lc, Dl, Dh, V, Al, Ah, Acl, Ach, bl, bh, Xl, Xh, Tl, Th, gl, gh, yl, yh) = box
    work = kr[7]
    lengths_ok = interval_structure(plo, phi, Alo, Ahi, Blo, Bhi, rows, Wl, Wh, U, Lx)
    if not structure_matrix(pc[0], pc[1], pc[2], Bc, Ac, rows, Wc, L):
        return UNDECIDED
    half_ranges(tmin, tmax, tmid, rho)
    # the centre decides which proof to try: inside if it is feasible (with the margin asked)
    basis = -1
    for k in range(wv.shape[0]):
        if not centre_tensions(Wc, wv[k], tmin, tmax, tmid, t, lo, hi, rhs, s, qp):
            if mu == 0.0 and m == n and lengths_ok and square_outside(plo, phi, pc, Alo, Ahi, Blo, Bhi, rows, bases,
                                                                      t, tmin, tmax, wv[k], box, kr):
                return OUTSIDE
            if outside_test(plo, phi, pc, Alo, Ahi, Blo, Bhi, rows, Wc, wv, tmid, rho, mu, facets, nu, best_nu, box):
                return OUTSIDE
            return UNDECIDED
        if k == 0:
            for j in range(m):
                slack[j] = min(t[j] - tmin[j], tmax[j] - t[j]) / max(tmax[j] - tmin[j], 1e-300)
            basis = best_basis(Wc, bases, slack, work)
    if mu > 0.0 and outside_test(plo, phi, pc, Alo, Ahi, Blo, Bhi, rows, Wc, wv, tmid, rho, mu, facets, nu, best_nu, box):
        return OUTSIDE
    if not lengths_ok or basis < 0:
        return UNDECIDED
    # inside: enclose the basis tensions over the box, the other cables' tensions fixed
    for k in range(wv.shape[0]):
        if not centre_tensions(Wc, wv[k], tmin, tmax, tmid, t, lo, hi, rhs, s, qp):
            return UNDECIDED
        if not basis_enclosure(Wl, Wh, bases, basis, t, tmin, tmax, wv[k], mu, Al, Ah, bl, bh, kr, Xl, Xh):
            return UNDECIDED
        if within(bases, basis, Xl, Xh, tmin, tmax):
            continue
        if not mean_value(plo, phi, pc, Alo, Ahi, Blo, Bhi, rows, bases, basis, t, tmin, tmax, wv[k], mu, box, kr):
            return UNDECIDED
        if not within(bases, basis, Xl, Xh, tmin, tmax):
            return UNDECIDED
    return INSIDE


@njit
def classify_block(k0, k1, lo, hi, Alo, Ahi, Blo, Bhi, Ac, Bc, rows, wv, tmin, tmax, mu, facets, bases, status):
    """:func:`classify_box` for boxes k0 .. k1 of ``lo``, ``hi`` (K, 3) [m] into ``status`` (K,) int8."""
    pc = np.empty(3)
    scr = make_scratch(rows.shape[0], Alo.shape[0])
    for k in range(k0, k1):
        for a in range(3):
            pc[a] = 0.5 * (lo[k, a] + hi[k, a])
        status[k] = classify_box(lo[k], hi[k], pc, Alo, Ahi, Blo, Bhi, Ac, Bc, rows, wv, tmin, tmax, mu,
                                 facets, bases, scr)
