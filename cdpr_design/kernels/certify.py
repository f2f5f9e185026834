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

Centred forms.  Where the first-order enclosures are too wide, both tests are
refined by the mean-value form about the box's centre *and the nominal
geometry*, in every variable v: the three position coordinates and, for each
cable j, the three coordinates of its outlet and the three of its
attachment's error e_j in effector coordinates (rotated attachment
B_j = R b_j + R e_j), each within its tolerance.  A function f of them lies in
f(c) + sum_v df/dv (over the whole box) (v - v_c) (the mean-value theorem along
the segment from the centre; the integral of values in a convex set lies in
it).  Column j of W depends only on p and cable j's own points:
dw_j/dA_jk = -dw_j/dp_k, and dw_j/de_jk = sum_i R_ik (dw_j/dp_i + [0 ; e_i x u_j])
(d_j = A_j - B_j - p).  So f(c) is taken at one geometry (a point, no width),
and each tolerance adds its own first-order term with its own sign, instead of
the whole tolerance box entering every column of W at once (which loses every
cancellation through W^-1 on robots whose moment rows are ill-conditioned).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import jitable, njit
from cdpr_design.kernels.geometry import structure_matrix
from cdpr_design.kernels.hsm import facet_normal
from cdpr_design.kernels.certify_interval import (half_ranges, interval_structure, krawczyk, krawczyk_box,
                                                  preconditioner, structure_derivative, support_gap)
from cdpr_design.kernels.interval import iadd, imul, iscale, isqr, isqrt, isub, up
from cdpr_design.kernels.hsm import make_scratch as make_qp_scratch
from cdpr_design.kernels.linalg import det_in_place, inverse_into
from cdpr_design.kernels.tension_qp import min_norm_tensions

#: box statuses (``cdpr_design.workspaces.certify`` names them)
INSIDE = 1
OUTSIDE = -1
UNDECIDED = 0

#: Passes of the centred form at most (:func:`centred`), and the narrowing of the enclosure's
#: total width below which another pass is tried
MEAN_VALUE_PASSES = 4
PASS_GAIN = 0.95

#: A box of positions: lower and upper corners ``lo``, ``hi`` and centre ``c`` (3,) [m] (``c`` a float
#: point within the box).
Box = namedtuple("Box", "lo hi c")
#: The robot's geometry: outlets in [Alo, Ahi] and rotated attachments in [Blo, Bhi] (m, 3) [m] (boxes
#: of half-width the tolerances), their nominal values ``Ac``, ``Bc`` (m, 3) [m] (within the boxes), and
#: the balanced wrench rows ``rows`` (n,) int64.  An attachment's error is e in [-tb_j, tb_j]^3 in
#: effector coordinates (``tb`` (m,) [m]), rotated: R b_j + ``Re`` e with ``Re`` (3, 3) the rotation,
#: its columns of the axes that carry no error (z of a planar design) zero; [Blo, Bhi] encloses it.
Geometry = namedtuple("Geometry", "Alo Ahi Blo Bhi Ac Bc rows Re tb")
#: What a box is tested for: the required-wrench vertices ``wv`` (nv, n) [N, N m], the tension bounds
#: ``tmin``, ``tmax`` (m,) [N], the capacity margin ``mu`` [N] (0: feasibility), and the cable subsets
#: ``facets`` (C(m, n-1), n-1) and ``bases`` (C(m, n), n) int64.
Task = namedtuple("Task", "wv tmin tmax mu facets bases")
#: Floats at the box's centre (:func:`classify_box`): the structure matrix ``Wc`` (n, m) and lengths
#: ``L``, the tension midpoints ``tmid`` and half-ranges ``rho``, facet normals ``nu``, ``best_nu``,
#: the centre's tensions ``t`` with the QP's bounds ``lo``, ``hi``, step ``s``, right-hand side ``rhs``,
#: each cable's ``slack`` and the QP's scratch ``qp``.
Centre = namedtuple("Centre", "Wc L tmid rho nu best_nu t lo hi s rhs slack qp")
#: Interval enclosures (lower, upper pairs) of a box: the structure matrix ``Wl``, ``Wh`` (n, m) with
#: unit vectors ``U`` (m, 3, 2) and lengths ``L`` (m, 2) over the box; the same at the centre and the
#: nominal geometry (``Wcl``, ``Wch``, ``Uc``, ``Lc``); the derivatives dW/dp_k ``Dl``, ``Dh`` (3, n, m)
#: and their scratch ``V`` (3, 2); the basis columns over the box ``Al``, ``Ah`` and at the centre ``Acl``,
#: ``Ach`` (n, n); right-hand sides ``bl``, ``bh``; the basis tensions over the box ``Xl``, ``Xh`` and
#: at the centre ``Tl``, ``Th``; a derivative's right-hand side ``gl``, ``gh``, one cable's ``cl``,
#: ``ch``, their preconditioned sum ``hl``, ``hh`` and its solution ``yl``, ``yh`` (n,).
Enclosures = namedtuple("Enclosures", "Wl Wh U L Wcl Wch Uc Lc Dl Dh V Al Ah Acl Ach bl bh Xl Xh Tl Th "
                                      "gl gh cl ch hl hh yl yh")
#: The Krawczyk step's scratch (:func:`krawczyk`): the midpoint ``Am`` and its inverse ``Y``, ``C`` =
#: I - Y [A] in ``Cl``, ``Ch`` (n, n), ``xt``, ``zl``, ``zh`` (n,) and ``work`` (n, >= 2n).
KrawczykScratch = namedtuple("KrawczykScratch", "Am Y xt Cl Ch zl zh work")
#: The work arrays of :func:`classify_box` (:func:`make_scratch`).
Scratch = namedtuple("Scratch", "centre box kr")


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
def outside_test(P, G, T, C, E):
    """Whether the box ``P`` (:class:`Box`) is proven outside: for some wrench vertex, the facet
    most violated at the centre has its support gap below mu |nu| over the whole box (natural
    interval extension, then the centred form of :func:`centred_gap`).  ``C``: the centre's floats
    (:class:`Centre`: ``Wc``, ``tmid``, ``rho``; ``nu``, ``best_nu`` scratch); ``E``: the box's
    enclosures (:class:`Enclosures`, ``Wl``, ``Wh``, ``U``, ``L`` filled)."""
    n, m = C.Wc.shape
    for k in range(T.wv.shape[0]):
        worst = np.inf
        for c in range(T.facets.shape[0]):
            if not facet_normal(C.Wc, T.facets[c], C.nu):
                continue
            half = 0.0
            gap = 0.0
            for j in range(m):
                lj = 0.0
                for i in range(n):
                    lj += C.nu[i] * C.Wc[i, j]
                half += abs(lj) * C.rho[j]
                gap += lj * C.tmid[j]
            for i in range(n):
                gap -= C.nu[i] * T.wv[k, i]
            s = half - abs(gap)
            if s < worst:
                worst = s
                for i in range(n):
                    C.best_nu[i] = C.nu[i]
        if not (worst < T.mu):
            continue
        ql, qh = 0.0, 0.0
        for i in range(n):
            pl, ph = isqr(C.best_nu[i], C.best_nu[i])
            ql, qh = iadd(ql, qh, pl, ph)
        nl, nh = isqrt(ql, qh)
        ml, mh = iscale(T.mu, nl, nh)
        sl, sh = support_gap(C.best_nu, E.Wl, E.Wh, C.tmid, C.rho, T.wv[k])
        if sh < ml:
            return True
        sh = centred_gap(P, G, C.best_nu, C.tmid, C.rho, T.wv[k], E)
        if sh < ml:
            return True
    return False


@njit
def derivatives(G, U, L, E):
    """Enclose dW/dp_k into ``E.Dl[k]``, ``E.Dh[k]`` (n, m), k = 0, 1, 2, from the unit vectors ``U``
    (m, 3, 2) and lengths ``L`` (m, 2) enclosed over a box (:func:`structure_derivative`)."""
    for axis in range(3):
        structure_derivative(axis, U, L, G.Blo, G.Bhi, G.rows, E.Dl[axis], E.Dh[axis], E.V)


@njit
def cable_term(G, E, U, j, kind, axis):
    """One geometric variable of cable j, ``kind`` 0: coordinate ``axis`` of its outlet, 1: the
    error along effector axis ``axis`` of its attachment.  Writes into [E.cl, E.ch] (n,) the
    derivative of column j of W over a box with respect to it (dw_j/da_k = -dw_j/dp_k;
    dw_j/de_k = sum_i Re_ik (dw_j/dp_i + [0 ; e_i x u_j]), d_j = a_j - R b_j - Re e - p), from
    ``E.Dl``, ``E.Dh`` (:func:`derivatives`) and the unit vectors ``U`` (m, 3, 2) over that box, and returns
    the interval of the variable minus its nominal value ((0, 0) when it has no extent: skip it)."""
    rows = G.rows
    n = rows.shape[0]
    if kind == 0:
        if not (G.Ahi[j, axis] > G.Alo[j, axis]):
            return 0.0, 0.0
        for k in range(n):
            E.cl[k], E.ch[k] = -E.Dh[axis, k, j], -E.Dl[axis, k, j]
        return isub(G.Alo[j, axis], G.Ahi[j, axis], G.Ac[j, axis], G.Ac[j, axis])
    if not (G.tb[j] > 0.0) or (G.Re[0, axis] == 0.0 and G.Re[1, axis] == 0.0 and G.Re[2, axis] == 0.0):
        return 0.0, 0.0
    for k in range(n):
        r = rows[k]
        sl, sh = 0.0, 0.0
        for i in range(3):
            dl, dh = E.Dl[i, k, j], E.Dh[i, k, j]
            if r >= 3:  # moment row c: (e_i x u)_c = -u_(i+2) for c = i+1, u_(i+1) for c = i+2
                c = r - 3
                if c == (i + 1) % 3:
                    q = (i + 2) % 3
                    dl, dh = isub(dl, dh, U[j, q, 0], U[j, q, 1])
                elif c == (i + 2) % 3:
                    q = (i + 1) % 3
                    dl, dh = iadd(dl, dh, U[j, q, 0], U[j, q, 1])
            pl, ph = iscale(G.Re[i, axis], dl, dh)
            sl, sh = iadd(sl, sh, pl, ph)
        E.cl[k], E.ch[k] = sl, sh
    return -G.tb[j], G.tb[j]


@njit
def centred_gap(P, G, nu, tmid, rho, w, E):
    """An upper bound over the box ``P`` and the geometry ``G`` of the support gap s
    (:func:`support_gap`) by centred forms about the box's centre and the nominal geometry.

    Where the sign sigma_j of l_j = nu . w_j is proven constant over the box (natural
    extension), and the sign sigma_g of the gap g = nu . (W t_mid - w) is, the part
    F = sum_j rho_j sigma_j l_j - sigma_g g of s is smooth and lies in
    F(c) + sum_v dF/dv (box) (v - v_c), dF/dv = sum_j (rho_j sigma_j - sigma_g t_mid,j)
    nu . dw_j/dv over the position coordinates and each cable's outlet and attachment
    coordinates (module docstring); each l_j of unknown sign (the facet's own cables, 0 at the
    centre) adds rho_j max |l_j(c) + sum_v nu . dw_j/dv (box) (v - v_c)|.  ``inf`` when the
    gap's sign is not proven.  ``E``: :class:`Enclosures` with the box's filled."""
    n, m = E.Wl.shape
    sig = np.empty(m)
    El = np.empty(m)
    Eh = np.empty(m)
    cl, ch = 0.0, 0.0
    for j in range(m):
        ll, lh = 0.0, 0.0
        for i in range(n):
            pl, ph = iscale(nu[i], E.Wl[i, j], E.Wh[i, j])
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
    # F(c) and the l_j(c), from the structure matrix at the centre and the nominal geometry
    interval_structure(P.c, P.c, G.Ac, G.Ac, G.Bc, G.Bc, G.rows, E.Wcl, E.Wch, E.Uc, E.Lc)
    fl, fh = 0.0, 0.0
    for i in range(n):
        pl, ph = iscale(sg * nu[i], w[i], w[i])
        fl, fh = iadd(fl, fh, pl, ph)
    for j in range(m):
        ll, lh = 0.0, 0.0
        for i in range(n):
            pl, ph = iscale(nu[i], E.Wcl[i, j], E.Wch[i, j])
            ll, lh = iadd(ll, lh, pl, ph)
        El[j], Eh[j] = ll, lh
        kl, kh = isub(rho[j] * sig[j], rho[j] * sig[j], sg * tmid[j], sg * tmid[j])
        pl, ph = imul(kl, kh, ll, lh)
        fl, fh = iadd(fl, fh, pl, ph)
    derivatives(G, E.U, E.L, E)
    for j in range(m):
        kl, kh = isub(rho[j] * sig[j], rho[j] * sig[j], sg * tmid[j], sg * tmid[j])
        for v in range(9):  # the position's coordinates, then cable j's outlet's, then its attachment's
            axis = v % 3
            if v < 3:
                if not (P.hi[axis] > P.lo[axis]):
                    continue
                for i in range(n):
                    E.cl[i], E.ch[i] = E.Dl[axis, i, j], E.Dh[axis, i, j]
                dl, dh = isub(P.lo[axis], P.hi[axis], P.c[axis], P.c[axis])
            else:
                dl, dh = cable_term(G, E, E.U, j, v // 3 - 1, axis)
                if dl == 0.0 and dh == 0.0:
                    continue
            al, ah = 0.0, 0.0
            for i in range(n):
                pl, ph = iscale(nu[i], E.cl[i], E.ch[i])
                al, ah = iadd(al, ah, pl, ph)
            al, ah = imul(al, ah, dl, dh)
            pl, ph = imul(kl, kh, al, ah)
            fl, fh = iadd(fl, fh, pl, ph)
            if sig[j] == 0.0:
                El[j], Eh[j] = iadd(El[j], Eh[j], al, ah)
    for j in range(m):
        if sig[j] == 0.0:
            pl, ph = iscale(rho[j], 0.0, max(-El[j], Eh[j]))
            fl, fh = iadd(fl, fh, pl, ph)
    return fh


@jitable
def make_scratch(n, m):
    """The work arrays of :func:`classify_box` for ``n`` DOF and ``m`` cables (one set per block of
    boxes): a :class:`Scratch` of the centre's floats (:class:`Centre`), the box's enclosures
    (:class:`Enclosures`) and the Krawczyk step's scratch (:class:`KrawczykScratch`)."""
    centre = Centre(np.empty((n, m)), np.empty(m), np.empty(m), np.empty(m), np.empty(n), np.empty(n),
                    np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(n), np.empty(m),
                    make_qp_scratch(n, m, 1))
    box = Enclosures(np.empty((n, m)), np.empty((n, m)), np.empty((m, 3, 2)), np.empty((m, 2)),
                     np.empty((n, m)), np.empty((n, m)), np.empty((m, 3, 2)), np.empty((m, 2)),
                     np.empty((3, n, m)), np.empty((3, n, m)), np.empty((3, 2)), np.empty((n, n)), np.empty((n, n)),
                     np.empty((n, n)), np.empty((n, n)), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
                     np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
                     np.empty(n), np.empty(n), np.empty(n))
    kr = KrawczykScratch(np.empty((n, n)), np.empty((n, n)), np.empty(n), np.empty((n, n)), np.empty((n, n)),
                         np.empty(n), np.empty(n), np.empty((n, max(2 * n, 2))))
    return Scratch(centre, box, kr)


@njit
def basis_enclosure(Wl, Wh, T, basis, t, w, Al, Ah, bl, bh, kr, Xl, Xh):
    """Enclose into [Xl, Xh] (n,) the tensions of the basis cables ``T.bases[basis]`` that balance
    every wrench of w + [-mu, mu]^n (n,) (mu = ``T.mu``) for every structure matrix in [Wl, Wh]
    (n, m), the other cables held at ``t`` clipped to their bounds.  ``Al``, ``Ah`` receive the
    basis columns; ``kr``: :class:`KrawczykScratch`.  False when regularity is not proven."""
    n, m = Wl.shape
    bases = T.bases
    for i in range(n):
        for j in range(n):
            Al[i, j] = Wl[i, bases[basis, j]]
            Ah[i, j] = Wh[i, bases[basis, j]]
        bl[i], bh[i] = iadd(w[i], w[i], -T.mu, T.mu)
    for j in range(m):
        if in_basis(bases, basis, j) >= 0:
            continue
        tj = min(max(t[j], T.tmin[j]), T.tmax[j])
        for i in range(n):
            pl, ph = iscale(tj, Wl[i, j], Wh[i, j])
            bl[i], bh[i] = isub(bl[i], bh[i], pl, ph)
    return krawczyk(Al, Ah, bl, bh, kr.Am, kr.Y, kr.xt, kr.Cl, kr.Ch, kr.zl, kr.zh, Xl, Xh, kr.work)


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
def basis_tension(T, basis, t, Xl, Xh, j):
    """Cable j's tension: its enclosure [Xl[q], Xh[q]] when it is basis cable q of ``T.bases[basis]``,
    else ``t[j]`` clipped to its bounds (held fixed)."""
    q = in_basis(T.bases, basis, j)
    if q >= 0:
        return Xl[q], Xh[q]
    tj = min(max(t[j], T.tmin[j]), T.tmax[j])
    return tj, tj


@njit
def add_preconditioned(Y, cl, ch, dl, dh, hl, hh):
    """[h] += (Y [c]) [d] into [hl, hh] (n,), for the float matrix ``Y`` (n, n), the interval
    vector [cl, ch] (n,) and the interval [dl, dh]."""
    n = Y.shape[0]
    for i in range(n):
        sl, sh = 0.0, 0.0
        for k in range(n):
            pl, ph = iscale(Y[i, k], cl[k], ch[k])
            sl, sh = iadd(sl, sh, pl, ph)
        pl, ph = imul(sl, sh, dl, dh)
        hl[i], hh[i] = iadd(hl[i], hh[i], pl, ph)


@njit
def centre_enclosure(P, G, T, basis, t, w, scr):
    """Enclose into [E.Tl, E.Th] (n,) (``E = scr.box``) the basis tensions at the box's centre for
    every geometry within tolerance, by the centred form in the geometric variables about the
    nominal geometry (module docstring):

        t_B(c, v) in t_B(c, v_c) - y,   y = [W_B(c, .)]^-1 sum_v g_v (v - v_c),   g_v = (dw_j/dv) t_j

    over each cable j's outlet coordinates and attachment errors v, with dw_j/dv, W_B and t_B
    enclosed at the centre over the tolerance boxes (the other cables at ``t`` clipped to their
    bounds); t_B(c, v_c) is enclosed at one point (:func:`basis_enclosure`); y by
    :func:`krawczyk_box` about 0, its right-hand side sum_v (Y g_v)(v - v_c) preconditioned term by
    term with the midpoint inverse Y of [W_B(c, .)] (so each variable keeps its own signs through
    Y).  False when a step is not proven."""
    E, kr = scr.box, scr.kr
    n = G.rows.shape[0]
    m = G.Alo.shape[0]
    for i in range(n):
        E.yl[i] = 0.0
        E.yh[i] = 0.0
    tolerance = False
    for j in range(m):
        tolerance = tolerance or G.tb[j] > 0.0
        for a in range(3):
            tolerance = tolerance or G.Ahi[j, a] > G.Alo[j, a]
    if tolerance:
        interval_structure(P.c, P.c, G.Alo, G.Ahi, G.Blo, G.Bhi, G.rows, E.Wcl, E.Wch, E.Uc, E.Lc)
        if not basis_enclosure(E.Wcl, E.Wch, T, basis, t, w, E.Acl, E.Ach, E.bl, E.bh, kr, E.Tl, E.Th):
            return False
        beta = preconditioner(E.Acl, E.Ach, kr.Am, kr.Y, kr.Cl, kr.Ch, kr.work)
        derivatives(G, E.Uc, E.Lc, E)
        for i in range(n):
            E.hl[i] = 0.0
            E.hh[i] = 0.0
        for j in range(m):
            tl, th = basis_tension(T, basis, t, E.Tl, E.Th, j)
            for v in range(6):
                dl, dh = cable_term(G, E, E.Uc, j, v // 3, v % 3)
                if dl == 0.0 and dh == 0.0:
                    continue
                for i in range(n):
                    E.cl[i], E.ch[i] = imul(E.cl[i], E.ch[i], tl, th)
                add_preconditioned(kr.Y, E.cl, E.ch, dl, dh, E.hl, E.hh)
        for i in range(n):
            kr.xt[i] = 0.0
        if not krawczyk_box(kr.xt, E.hl, E.hh, kr.Cl, kr.Ch, beta, E.yl, E.yh, kr.work):
            return False
    interval_structure(P.c, P.c, G.Ac, G.Ac, G.Bc, G.Bc, G.rows, E.Wcl, E.Wch, E.Uc, E.Lc)
    if not basis_enclosure(E.Wcl, E.Wch, T, basis, t, w, E.Acl, E.Ach, E.bl, E.bh, kr, E.Tl, E.Th):
        return False
    for q in range(n):
        E.Tl[q], E.Th[q] = isub(E.Tl[q], E.Th[q], E.yl[q], E.yh[q])
    return True


@njit
def mean_value(P, G, T, basis, t, scr):
    """Refine the enclosure [Xl, Xh] of the basis tensions over the box (``scr.box``: the basis
    columns over the box in ``Al``, ``Ah``; the centre's enclosure for every geometry in ``Tl``,
    ``Th``, :func:`centre_enclosure`) by the centred (mean-value) form in the position:

        t_B(p, v) in t_B(c, v) - y,   y = [W_B]^-1 sum_k g_k (p_k - c_k),   g_k = sum_j (dw_j/dp_k) t_j

    with dw_j/dp_k, W_B and t_B (in [X]) enclosed over the whole box (positions and geometries),
    the other cables at ``t`` clipped to their bounds; y by :func:`krawczyk_box` about 0 with the
    right-hand side preconditioned term by term.  The result is intersected into [Xl, Xh].  False
    when a step is not proven."""
    E, kr = scr.box, scr.kr
    n = G.rows.shape[0]
    m = G.Alo.shape[0]
    beta = preconditioner(E.Al, E.Ah, kr.Am, kr.Y, kr.Cl, kr.Ch, kr.work)
    if not (beta < 1.0):
        return False
    for i in range(n):
        E.hl[i] = 0.0
        E.hh[i] = 0.0
    derivatives(G, E.U, E.L, E)
    for axis in range(3):
        if not (P.hi[axis] > P.lo[axis]):
            continue
        for i in range(n):
            E.gl[i] = 0.0
            E.gh[i] = 0.0
        for j in range(m):
            tl, th = basis_tension(T, basis, t, E.Xl, E.Xh, j)
            for i in range(n):
                pl, ph = imul(E.Dl[axis, i, j], E.Dh[axis, i, j], tl, th)
                E.gl[i], E.gh[i] = iadd(E.gl[i], E.gh[i], pl, ph)
        dl, dh = isub(P.lo[axis], P.hi[axis], P.c[axis], P.c[axis])
        add_preconditioned(kr.Y, E.gl, E.gh, dl, dh, E.hl, E.hh)
    for i in range(n):
        kr.xt[i] = 0.0
    if not krawczyk_box(kr.xt, E.hl, E.hh, kr.Cl, kr.Ch, beta, E.yl, E.yh, kr.work):
        return False
    for q in range(n):
        lo_q, hi_q = isub(E.Tl[q], E.Th[q], E.yl[q], E.yh[q])
        E.Xl[q] = max(E.Xl[q], lo_q)
        E.Xh[q] = min(E.Xh[q], hi_q)
    return True


@njit
def square_outside(P, G, T, t, w, scr):
    """Square case (m = n, ``T.mu`` = 0): whether the unique tensions t = W^-1 w, enclosed over the
    box by Krawczyk (first order, then the centred form), have a component wholly outside its
    bounds at every pose of the box and geometry (which also proves W regular there)."""
    E = scr.box
    if not basis_enclosure(E.Wl, E.Wh, T, 0, t, w, E.Al, E.Ah, E.bl, E.bh, scr.kr, E.Xl, E.Xh):
        return False
    return beyond(T.bases, E.Xl, E.Xh, T.tmin, T.tmax) or centred(P, G, T, 0, t, w, scr, True)


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
def classify_box(P, G, T, scr):
    """The status of one box of positions ``P`` (:class:`Box`) for the geometry ``G``
    (:class:`Geometry`) and the task ``T`` (:class:`Task`): INSIDE, OUTSIDE or UNDECIDED (module
    docstring).  ``scr`` from :func:`make_scratch`."""
    m = G.Alo.shape[0]
    n = G.rows.shape[0]
    C, E, kr = scr.centre, scr.box, scr.kr
    lengths_ok = interval_structure(P.lo, P.hi, G.Alo, G.Ahi, G.Blo, G.Bhi, G.rows, E.Wl, E.Wh, E.U, E.L)
    if not structure_matrix(P.c[0], P.c[1], P.c[2], G.Bc, G.Ac, G.rows, C.Wc, C.L):
        return UNDECIDED
    half_ranges(T.tmin, T.tmax, C.tmid, C.rho)
    # the centre decides which proof to try: inside if it is feasible (with the margin asked)
    basis = -1
    for k in range(T.wv.shape[0]):
        if not centre_tensions(C.Wc, T.wv[k], T.tmin, T.tmax, C.tmid, C.t, C.lo, C.hi, C.rhs, C.s, C.qp):
            if T.mu == 0.0 and m == n and lengths_ok and square_outside(P, G, T, C.t, T.wv[k], scr):
                return OUTSIDE
            if outside_test(P, G, T, C, E):
                return OUTSIDE
            return UNDECIDED
        if k == 0:
            for j in range(m):
                C.slack[j] = min(C.t[j] - T.tmin[j], T.tmax[j] - C.t[j]) / max(T.tmax[j] - T.tmin[j], 1e-300)
            basis = best_basis(C.Wc, T.bases, C.slack, kr.work)
    if T.mu > 0.0 and outside_test(P, G, T, C, E):
        return OUTSIDE
    if not lengths_ok or basis < 0:
        return UNDECIDED
    # inside: enclose the basis tensions over the box, the other cables' tensions fixed
    for k in range(T.wv.shape[0]):
        if not centre_tensions(C.Wc, T.wv[k], T.tmin, T.tmax, C.tmid, C.t, C.lo, C.hi, C.rhs, C.s, C.qp):
            return UNDECIDED
        if not basis_enclosure(E.Wl, E.Wh, T, basis, C.t, T.wv[k], E.Al, E.Ah, E.bl, E.bh, kr, E.Xl, E.Xh):
            return UNDECIDED
        if within(T.bases, basis, E.Xl, E.Xh, T.tmin, T.tmax):
            continue
        if not centred(P, G, T, basis, C.t, T.wv[k], scr, False):
            return UNDECIDED
    return INSIDE


@njit
def centred(P, G, T, basis, t, w, scr, outside):
    """Whether the centred forms prove the basis tensions within their bounds (``outside`` False) or,
    for the square case's basis 0, one of them wholly beyond its bounds (True):
    :func:`centre_enclosure`, then :func:`mean_value` up to :data:`MEAN_VALUE_PASSES` times, each
    pass enclosing the derivatives with the basis tensions of the last (a pass that narrowed them
    narrows the next one's terms) while the enclosure's total width shrinks below
    :data:`PASS_GAIN` of the last."""
    E = scr.box
    if not centre_enclosure(P, G, T, basis, t, w, scr):
        return False
    for _ in range(MEAN_VALUE_PASSES):
        before = 0.0
        for q in range(E.Xl.shape[0]):
            before += E.Xh[q] - E.Xl[q]
        if not mean_value(P, G, T, basis, t, scr):
            return False
        if outside and beyond(T.bases, E.Xl, E.Xh, T.tmin, T.tmax):
            return True
        if not outside and within(T.bases, basis, E.Xl, E.Xh, T.tmin, T.tmax):
            return True
        after = 0.0
        for q in range(E.Xl.shape[0]):
            after += E.Xh[q] - E.Xl[q]
        if not (after < PASS_GAIN * before):
            return False
    return False


@njit
def classify_block(k0, k1, lo, hi, G, T, status):
    """:func:`classify_box` for boxes k0 .. k1 of ``lo``, ``hi`` (K, 3) [m] into ``status`` (K,) int8,
    for the geometry ``G`` (:class:`Geometry`) and the task ``T`` (:class:`Task`)."""
    pc = np.empty(3)
    scr = make_scratch(G.rows.shape[0], G.Alo.shape[0])
    for k in range(k0, k1):
        for a in range(3):
            pc[a] = 0.5 * (lo[k, a] + hi[k, a])
        status[k] = classify_box(Box(lo[k], hi[k], pc), G, T, scr)
