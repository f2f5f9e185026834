"""Exact minimum-2-norm cable tensions: Goldfarb-Idnani dual active set on the null space of W."""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import jitable, njit, njit_folded
from cdpr_design.kernels.linalg import householder_qr, orthogonalize_column
from cdpr_design.kernels.hsm import basis_factor


#: Relative tolerance (to the largest tension bound) of the QP's bound checks.
QP_TOL = 1e-11

#: The arrays of the null-space reduction W t = w -> t = t_p + N z (:func:`reduction` of a
#: :func:`~cdpr_design.kernels.hsm.make_scratch`): ``tab`` (n, m + n) the basis factorisation,
#: ``slot`` (m,), ``nbc`` (max(m - n, 1),), ``bcol`` (n,) its basis bookkeeping (int64), ``N``
#: (m, r) the orthonormal null basis, ``tp`` (m,) t_p [N], ``tb`` (m,) the basic solution [N].
#: The square case's whole scratch: a compiled function counts a reference to every array it is
#: handed on every call, so the square tensions (:func:`min_norm_tensions_square`, called many times
#: a pose by the sagging cables' fixed point) are handed these 7, not the scratch's 31.
Reduction = namedtuple("Reduction", "tab slot nbc bcol N tp tb")


@jitable
def reduction(scr):
    """The :data:`Reduction` arrays of the scratch ``scr`` (:func:`~cdpr_design.kernels.hsm.make_scratch`),
    the same arrays (not copies)."""
    return Reduction(scr[0], scr[18], scr[19], scr[20], scr[8], scr[9], scr[25])


@njit
def null_space(n, m, w, tab, N, tp, tb, nbc, bcol):
    """Orthonormal null basis ``N`` (m, r) and ``tp`` (m,) t_p = W^+ w [N] from the basis
    factorisation ``tab``, ``nbc``, ``bcol`` (:func:`~cdpr_design.kernels.hsm.basis_factor`).

    The columns of P [-F; I] span the null space of W; two passes of classical Gram-Schmidt make
    them orthonormal.  The basic solution ``tb`` (t_B = G w, t_N = 0) projected off the null space
    is the minimum-norm solution t_p = t_b - N N^T t_b.  The arrays of a :data:`Reduction`.
    """
    r = m - n
    for k in range(r):
        col = nbc[k]
        for j in range(m):
            N[j, k] = 0.0
        N[col, k] = 1.0
        for s in range(n):
            N[bcol[s], k] = -tab[s, col]
        s = 1.0 / orthogonalize_column(N, k, m)
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


@njit_folded
def qp_tolerance(m, tmin, tmax):
    """The bound tolerance of the QPs [N]: ``QP_TOL`` times the largest finite bound (at least 1 N)."""
    scale = 1.0
    for j in range(m):  # the finite bounds only: t_max = inf means no upper bound
        if math.isfinite(tmin[j]):
            scale = max(scale, abs(tmin[j]))
        if math.isfinite(tmax[j]):
            scale = max(scale, abs(tmax[j]))
    return QP_TOL * scale


@njit_folded
def project_null(m, r, tmin, tmax, t, scr):
    """The projection of :func:`goldfarb_idnani` (same inputs in ``scr``, same result): in closed
    form for one or two redundant cables (:func:`project_one`, :func:`project_two`), by the dual
    active-set method otherwise.  Returns False (``t`` NaN) when no tensions exist.  The sweeps'
    pose function makes the same choice inline (:func:`cdpr_design.kernels.pose.eval_general`)."""
    if r == 0:
        return square_projection(m, tmin, tmax, t, scr[9])
    if r == 1:
        return project_one(m, tmin, tmax, t, scr)
    if r == 2:
        return project_two(m, tmin, tmax, t, scr)
    return goldfarb_idnani(m, r, tmin, tmax, t, scr)


@njit
def square_projection(m, tmin, tmax, t, tp):
    """:func:`goldfarb_idnani` for r = 0 (as many cables as wrench rows): no null space, so the
    tensions are ``tp`` (scr[9], t_p = W^-1 w): clipped into the bounds when no bound is violated
    by more than :func:`qp_tolerance`, else none (``t`` NaN, False), as the dual method decides
    with no direction to move in."""
    tol = qp_tolerance(m, tmin, tmax)
    for j in range(m):
        if tp[j] - tmin[j] < -tol or tmax[j] - tp[j] < -tol:
            for i in range(m):
                t[i] = np.nan
            return False
    for j in range(m):
        t[j] = min(max(tp[j], tmin[j]), tmax[j])
    return True


@njit_folded
def _finish(m, r, tmin, tmax, t, N, tp, z0, z1, ok):
    """t = t_p + N z clipped into the bounds (``ok``), else NaN; returns ``ok``."""
    for j in range(m):
        if not ok:
            t[j] = np.nan
            continue
        s = tp[j] + N[j, 0] * z0
        if r == 2:
            s += N[j, 1] * z1
        t[j] = min(max(s, tmin[j]), tmax[j])
    return ok


@njit_folded
def project_one(m, tmin, tmax, t, scr):
    """:func:`goldfarb_idnani` for r = 1: the balancing tensions are t_p + z n, z on a line.

    z starts at 0 and moves to meet the most violated bound exactly, as long
    as every violated bound asks for the same direction; a bound violated the
    other way (or one z cannot change) proves that no tensions exist.  Every
    bound met at one step stays met at the next (z only moves away from it),
    so z ends at the end of the feasible interval nearest 0.  Violations up to
    :func:`qp_tolerance` count as met, as in the general method.
    """
    return line_projection(m, tmin, tmax, t, scr[8], scr[9], scr[30])


@njit
def line_projection(m, tmin, tmax, t, N, tp, H):
    """:func:`project_one` on the scratch's null basis ``N`` (scr[8]) and ``tp`` (scr[9]) themselves
    (see :func:`null_space`).  ``H`` is not used: the arguments of :func:`plane_projection`, so that
    a pose's code calls either alike (:func:`~cdpr_design.kernels.pose.eval_small`)."""
    tol = qp_tolerance(m, tmin, tmax)
    z = 0.0
    way = 0.0  # the direction z moves in: +1, -1 (0: not moved yet)
    for _ in range(m + 1):
        p = -1
        worst = tol
        up = True
        for j in range(m):
            v = tp[j] + N[j, 0] * z
            if tmin[j] - v > worst:
                worst, p, up = tmin[j] - v, j, True
            if v - tmax[j] > worst:
                worst, p, up = v - tmax[j], j, False
        if p < 0:
            break
        a = N[p, 0]
        need = (1.0 if a > 0.0 else -1.0) * (1.0 if up else -1.0)
        if a == 0.0 or need * way < 0.0:
            break
        way = need
        z = ((tmin[p] if up else tmax[p]) - tp[p]) / a
    # no bound violated (p < 0): t at z; else none exist.  One call, its ``ok`` not a constant:
    # numba compiles a function once per constant argument it is called with
    return _finish(m, 1, tmin, tmax, t, N, tp, z, 0.0, p < 0)


@njit_folded
def _half_plane(N, tp, tmin, tmax, m, c):
    """Bound ``c`` (c < m: t_c >= t_min; else t_(c-m) <= t_max) as g . z <= h: (g0, g1, h)."""
    if c < m:
        g0, g1, h = -N[c, 0], -N[c, 1], tp[c] - tmin[c]
    else:
        j = c - m
        g0, g1, h = N[j, 0], N[j, 1], tmax[j] - tp[j]
    return g0, g1, h


@njit_folded
def _inside(H, k, z0, z1, tol):
    """Whether z meets the first ``k`` half-planes ``H`` (rows g0, g1, h) to ``tol``."""
    inside = True
    a = 0
    while inside and a < k:
        inside = not H[a, 0] * z0 + H[a, 1] * z1 - H[a, 2] > tol
        a += 1
    return inside


@njit_folded
def project_two(m, tmin, tmax, t, scr):
    """:func:`goldfarb_idnani` for r = 2: the point nearest the origin of a polygon, in closed form.

    The dual active-set idea in the plane: z starts at 0; while a bound is
    violated, the most violated one joins the (at most two) bounds active at
    z, and z becomes the point nearest the origin of those at most three
    half-planes -- the best of the feet of the perpendiculars on their lines
    and of the corners of pairs, among those inside all of them.  Each step
    moves z further from the origin, so no set of active bounds repeats; at
    the end z is nearest the origin in a region containing the polygon, and
    inside it, hence the answer.  No candidate inside the half-planes proves
    that no tensions exist.  Violations up to :func:`qp_tolerance` count as met.
    """
    return plane_projection(m, tmin, tmax, t, scr[8], scr[9], scr[30])


@njit
def plane_projection(m, tmin, tmax, t, N, tp, H):
    """:func:`project_two` on the scratch's ``N`` (scr[8]), ``tp`` (scr[9]) and half-planes ``H``
    (scr[30]) themselves (see :func:`null_space`)."""
    tol = qp_tolerance(m, tmin, tmax)
    z0 = 0.0
    z1 = 0.0
    # the integers that reach a compiled call start as np.int64, not a literal: numba's type
    # inference would first see a literal (-1, 0) and compile the callee for it as well
    act0 = np.int64(-1)
    act1 = np.int64(-1)
    for _ in range(4 * m * m + 8):  # a guard: each step leaves z further from the origin
        # the most violated bound at z
        p = -1
        worst = tol
        for j in range(m):
            v = tp[j] + N[j, 0] * z0 + N[j, 1] * z1
            if tmin[j] - v > worst:
                worst = tmin[j] - v
                p = j
            if v - tmax[j] > worst:
                worst = v - tmax[j]
                p = j + m
        if p < 0:
            break
        k = np.int64(0)
        for c in (act0, act1, p):
            if c >= 0:
                H[k, 0], H[k, 1], H[k, 2] = _half_plane(N, tp, tmin, tmax, m, c)
                H[k, 3] = c
                k += 1
        best = np.inf
        z0n = z1n = 0.0
        new0 = -1
        new1 = -1
        for a in range(k):  # feet of the perpendiculars (only a line the origin is outside of)
            g2 = H[a, 0] * H[a, 0] + H[a, 1] * H[a, 1]
            if H[a, 2] < 0.0 and g2 > 0.0:
                s = H[a, 2] / g2
                c0 = s * H[a, 0]
                c1 = s * H[a, 1]
                d = c0 * c0 + c1 * c1
                if d < best and _inside(H, k, c0, c1, tol):
                    best, z0n, z1n, new0, new1 = d, c0, c1, int(H[a, 3]), -1
        for a in range(k):  # corners
            for b in range(a + 1, k):
                det = H[a, 0] * H[b, 1] - H[a, 1] * H[b, 0]
                na = H[a, 0] * H[a, 0] + H[a, 1] * H[a, 1]
                nb = H[b, 0] * H[b, 0] + H[b, 1] * H[b, 1]
                if not abs(det) > 1e-12 * math.sqrt(na * nb):
                    continue
                c0 = (H[a, 2] * H[b, 1] - H[b, 2] * H[a, 1]) / det
                c1 = (H[a, 0] * H[b, 2] - H[b, 0] * H[a, 2]) / det
                d = c0 * c0 + c1 * c1
                if d < best and _inside(H, k, c0, c1, tol):
                    best, z0n, z1n, new0, new1 = d, c0, c1, int(H[a, 3]), int(H[b, 3])
        if new0 < 0:  # the half-planes have no common point: neither has the polygon
            break
        z0, z1, act0, act1 = z0n, z1n, new0, new1
    # no bound violated (p < 0): t at z; else none exist (as in :func:`line_projection`).  ``H`` read
    # last (it always has rows), so that every array's last use is in the one exit block: numba then
    # counts no reference to them per call
    ok = _finish(m, 2, tmin, tmax, t, N, tp, z0, z1, p < 0)
    return ok & (H.shape[0] > 0)


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
    finite bound count as satisfied (an infinite bound is no bound); the result is clipped into the bounds.
    Returns False (``t`` NaN) when infeasible.
    """
    N, tp, J, RA, NA, VA = scr[8], scr[9], scr[10], scr[11], scr[12], scr[13]
    z, d, rdir, u, active = scr[14], scr[15], scr[16], scr[17], scr[24]
    tol = qp_tolerance(m, tmin, tmax)
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
    exactly by :func:`project_null`.  Writes ``t`` (m) [N]; returns False
    (``t`` NaN) when the bounds admit no solution or rank W < n.  ``scr``
    from :func:`make_scratch`.
    """
    n, m = W.shape
    red = reduction(scr)
    return (_reduced(W, w, t, red.tab, red.slot, red.nbc, red.bcol, red.N, red.tp, red.tb)
            and project_null(m, m - n, tmin, tmax, t, scr))


@njit_folded
def min_norm_tensions_square(W, w, tmin, tmax, t, red):
    """:func:`min_norm_tensions` for m = n (the same numbers) in the :data:`Reduction` ``red``,
    compiling only the square case (:func:`square_projection`) and none of the redundant methods:
    the tensions are unique."""
    return (_reduced(W, w, t, red.tab, red.slot, red.nbc, red.bcol, red.N, red.tp, red.tb)
            and square_projection(W.shape[1], tmin, tmax, t, red.tp))


@njit_folded
def _reduced(W, w, t, tab, slot, nbc, bcol, N, tp, tb):
    """``t`` NaN, then the null-space reduction of W t = w into the :data:`Reduction`'s arrays (the
    basis factorisation, the null basis N and t_p: :func:`null_space`); False when rank W < n."""
    n, m = W.shape
    for j in range(m):
        t[j] = np.nan
    if not basis_factor(W, tab, slot, nbc, bcol):
        return False
    null_space(n, m, w, tab, N, tp, tb, nbc, bcol)
    return True
