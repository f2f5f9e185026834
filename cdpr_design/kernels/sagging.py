"""Inverse statics with heavy, elastic cables: one pose and batched grids.

Each cable is Irvine's elastic catenary (:mod:`cdpr_design.kernels.catenary`)
in the vertical plane through its outlet A and its attachment B.  Its force on
the effector is along the cable's tangent at B, which lies below the chord, so
the structure matrix depends on the tensions.  The tensions are found as a
fixed point:

1. start from the straight-cable minimum-norm tensions t;
2. for every cable, find the shape whose effector-end tension is t_i
   (:func:`cable_for_tension`: the end-force angle and the unstretched length
   by Newton's method) and build the structure matrix W(t) from the end-force
   directions.  A heavy cable cannot pull with less than its least tension
   (:func:`least_tension`, the tension of a cable paid out until it pulls
   least; it is never slack with zero force): asked for less, it takes that
   shape, and its lower bound becomes that tension;
3. stop when W(t) t balances the required wrench to 1e-13 of the forces involved
   and t no longer changes;
   otherwise take the minimum-norm tensions of W(t) under the bounds shifted
   so that they hold along the whole cable (the largest tension, at the outlet
   for a hanging cable, <= t_max; the smallest >= t_min) and go to 2.

The map t -> t' contracts with a factor of about w L / (2 T) (a cable's weight
over twice its tension), so a few iterations suffice for taut cables.  The
result is the minimum-norm distribution for the cables' own equilibrium
shapes (for m = n the only one).  Every pose ends with a status
(:data:`SAG_OK` ...): a pose whose shapes did not converge is never reported
with numbers.

Vertical: ``up`` is the unit vector against gravity; for a planar robot it
lies in the plane of motion, so every cable plane is that plane.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from cdpr_design.kernels._jit import njit, njit_parallel
from cdpr_design.kernels.catenary import CAT_CONVERGED, _closure_jac, catenary_inverse, catenary_sag
from cdpr_design.kernels.geometry import fill_column
from cdpr_design.kernels.hsm import make_scratch
from cdpr_design.kernels.pose import eval_general, eval_pose
from cdpr_design.kernels.tension_qp import min_norm_tensions

#: Status of a pose (``status`` column of a sagging sweep).
#: Converged: feasible or not by its margin and tensions.
SAG_OK = 0
#: No tensions >= t_min balance the load (with the cables' shapes): infeasible, margin NaN.
SAG_NO_TENSIONS = 1
#: No catenary: the load needs a heavy cable to pull with less than its least tension
#: (:func:`least_tension`; no tensions balance the load once it is held there), or a
#: cable's shape could not be found: infeasible, margin NaN.
SAG_NO_CATENARY = 2
#: The fixed point did not converge in the iterations allowed: infeasible, margin NaN.
SAG_NOT_CONVERGED = 3
#: A zero-length cable or a rank-deficient structure matrix: infeasible, margin NaN.
SAG_SINGULAR = 4

#: An effector-end tension at or below SLACK times the largest is a slack cable
#: (a zero lower bound reached) if it is weightless or hangs straight down from its
#: outlet: it exerts no force and its length is undetermined.  A heavy cable is
#: never slack: it holds at least its least tension (:func:`least_tension`).
SLACK = 1e-9
#: Equilibrium tolerance of the fixed point: |W t - w| <= SAG_TOL (1 + |w| + max t) [N].
SAG_TOL = 1e-13

# per-cable work columns (array ``cw`` (m, NCW))
_X, _Z, _UX, _UY, _UZ, _TH, _L0, _H, _VB, _LO, _HI, _TA = range(12)
# the cable's least tension and its shape (:func:`least_tension`; NaN until needed)
_TM, _HM, _VM, _LM = range(12, 16)
# the fixed point's previous residual g - x and unrelaxed iterate g (for the relaxation)
_RP, _GP = 16, 17
# the tension of the shape in (th, L0), and the previous shape's (tension, th, L0): a secant start
_TAU, _TP, _THP, _LP = range(18, 22)
NCW = 22


@njit
def _vertical_length(Z, tau, w, EA):
    """Unstretched length [m] of a vertical cable of height Z (A above B if > 0) whose
    effector-end tension is tau; NaN when none (a cable below B heavier than tau)."""
    k = 1.0 / EA
    if Z > 0.0:
        # Z = L0 (1 + tau/EA) + w L0^2 / (2 EA)
        a = 0.5 * w * k
        b = 1.0 + tau * k
        L0 = Z / b if a == 0.0 else 2.0 * Z / (b + math.sqrt(b * b + 4.0 * a * Z))
        return L0
    # A below B: the cable hangs from B; -Z = L0 (1 + tau/EA) - w L0^2 / (2 EA), V <= 0 needs tau >= w L0
    a = 0.5 * w * k
    b = 1.0 + tau * k
    disc = b * b - 4.0 * a * (-Z)
    if disc < 0.0:
        return math.nan
    L0 = -Z / b if a == 0.0 else 2.0 * (-Z) / (b + math.sqrt(disc))
    if w * L0 > tau:
        return math.nan
    return L0


@njit
def _fold_slope(X, Z, L0, w, EA, H0, VB0):
    """(g, H, VB) of the cable of length L0 [m] spanning X, Z: g = (H, VB) . J^-1 (H, VA), J the
    flexibility d(X, Z)/d(H, VB), has the sign of -dT_B/dL0 (> 0: the taut side); NaN: no shape."""
    H, VB, st, _ = catenary_inverse(X, Z, L0, w, EA, H0, VB0, 1e-15, 100)
    if st != CAT_CONVERGED or not (H > 0.0):
        return math.nan, math.nan, math.nan
    a, b, c, d = _closure_jac(H, VB, L0, w, EA)[2:]
    VA = VB + w * L0
    det = a * d - b * c
    return (H * (d * H - b * VA) + VB * (a * VA - c * H)) / det, H, VB


@njit
def least_tension(X, Z, w, EA):
    """The least effector-end tension [N] of a heavy cable (w > 0) spanning X, Z [m], and its shape.

    Paying out cable first relieves the effector end, then, once the cable hangs
    deeply, loads it again: over the unstretched lengths L0 the tension T_B has
    one minimum, the "slack" state of a heavy cable, which cannot pull with less
    (about 0.75 w X for a horizontal span).  Found where dT_B/dL0 = 0, i.e.
    (H, VB) . J^-1 (H, VA) = 0 (J the flexibility; d(H, VB)/dL0 = -J^-1 (H, VA)
    (1/T_A + 1/EA)), by regula falsi (Illinois) on ln L0 from a bracket.
    Returns (tau_min, H, VB, L0); a vertical cable hanging from its outlet (X = 0,
    Z > 0) returns 0 (it may be slack); NaN when the bracket is not found.
    """
    nan = math.nan
    c = math.hypot(X, Z)
    if X <= 1e-14 * c:
        if Z > 0.0:
            return 0.0, 0.0, 0.0, nan
        # hanging from B down to A, no force at A: -Z = L0 + w L0^2 / (2 EA)
        L0 = 2.0 * (-Z) / (1.0 + math.sqrt(1.0 + 2.0 * w * (-Z) / EA))
        return w * L0, 0.0, -w * L0, L0
    inext = math.isinf(EA)
    la = c * (1.0 + 1e-6) if inext else c
    ga, ha, va = _fold_slope(X, Z, la, w, EA, nan, nan)
    k = 0
    while not (ga > 0.0) and k < 60 and not inext:
        la *= 0.5
        ga, ha, va = _fold_slope(X, Z, la, w, EA, nan, nan)
        k += 1
    lb = 2.0 * c
    gb, hb, vb = _fold_slope(X, Z, lb, w, EA, nan, nan)
    k = 0
    while not (gb < 0.0) and k < 60 and math.isfinite(gb):
        lb *= 2.0
        gb, hb, vb = _fold_slope(X, Z, lb, w, EA, hb, vb)
        k += 1
    if not (ga > 0.0 and gb < 0.0):
        return nan, nan, nan, nan
    xa, xb = math.log(la), math.log(lb)
    side = 0
    for _ in range(200):
        if xb - xa <= 1e-13:
            break
        x = (xa * gb - xb * ga) / (gb - ga)
        if not (xa < x < xb):
            x = 0.5 * (xa + xb)
        g, h, v = _fold_slope(X, Z, math.exp(x), w, EA, ha if side <= 0 else hb, va if side <= 0 else vb)
        if not math.isfinite(g):
            return nan, nan, nan, nan
        if g > 0.0:
            xa, ga, ha, va = x, g, h, v
            if side == 1:
                gb *= 0.5
            side = 1
        elif g < 0.0:
            xb, gb, hb, vb = x, g, h, v
            if side == -1:
                ga *= 0.5
            side = -1
        else:
            return math.hypot(h, v), h, v, math.exp(x)
    ta = math.hypot(ha, va)
    tb = math.hypot(hb, vb)
    if ta <= tb:
        return ta, ha, va, math.exp(xa)
    return tb, hb, vb, math.exp(xb)


@njit
def cable_for_tension(X, Z, tau, w, EA, th0, L00, maxit):
    """The shape of a cable spanning X, Z [m] whose tension at the effector is tau [N].

    Unknowns: the angle th [rad] of the end force at B above the horizontal
    (H = tau cos th, VB = tau sin th) and the unstretched length L0 [m];
    equations: the catenary closure X(H, VB, L0) = X, Z(H, VB, L0) = Z.  Newton's
    method with the analytic Jacobian (d(X, Z)/d(H, VB) from the catenary kernel,
    d(X, Z)/dL0 = (H, VA) (1/T_A + 1/EA)) and backtracking on the residual,
    started from (th0, L00) (NaN: the chord angle lowered by w c cos(chord)/(2 tau),
    and the chord shortened by the stretch).  This finds the taut branch, the one
    that tends to the straight cable as w -> 0.  Returns (H, VB, L0, ok).
    """
    nan = math.nan
    c = math.hypot(X, Z)
    if not (tau > 0.0) or not (c > 0.0):
        return nan, nan, nan, False
    if w == 0.0:
        return tau * X / c, tau * Z / c, c / (1.0 + tau / EA), True
    if X <= 1e-14 * c:
        L0 = _vertical_length(Z, tau, w, EA)
        if not (L0 > 0.0):
            return nan, nan, nan, False
        return 0.0, (tau if Z > 0.0 else -tau), L0, True
    if math.isfinite(th0) and math.isfinite(L00) and L00 > 0.0:
        th, L0 = th0, L00
    else:
        alpha = math.atan2(Z, X)
        th = alpha - w * c * math.cos(alpha) / (2.0 * tau)
        th = max(min(th, 1.5), -1.5)
        L0 = c / (1.0 + tau / EA)
    floor = (64.0 * 2.220446049250313e-16 * c) ** 2
    phi = math.inf
    # the closure and its Jacobian at (th, L0): the accepted trial point's, or evaluated here
    cj = _closure_jac(tau * math.cos(th), tau * math.sin(th), L0, w, EA)
    for _ in range(maxit):
        H = tau * math.cos(th)
        VB = tau * math.sin(th)
        Xc, Zc, a, b, cc, d = cj
        rx = Xc - X
        rz = Zc - Z
        phi = rx * rx + rz * rz
        if phi <= floor:
            return H, VB, L0, True
        VA = VB + w * L0
        k = 1.0 / math.hypot(H, VA) + 1.0 / EA
        j11 = -VB * a + H * b
        j21 = -VB * cc + H * d
        j12 = H * k
        j22 = VA * k
        det = j11 * j22 - j12 * j21
        if not (det != 0.0 and math.isfinite(det)):
            return nan, nan, nan, False
        dth = -(j22 * rx - j12 * rz) / det
        dL = -(-j21 * rx + j11 * rz) / det
        # damped: |th| < pi/2 (H > 0), L0 > 0, residual decreasing
        step = 1.0
        if abs(dth) > 0.5:
            step = 0.5 / abs(dth)
        while L0 + step * dL <= 0.0 or abs(th + step * dth) >= 0.5 * math.pi:
            step *= 0.5
        accepted = False
        for _ in range(40):
            th1 = th + step * dth
            L1 = L0 + step * dL
            cj1 = _closure_jac(tau * math.cos(th1), tau * math.sin(th1), L1, w, EA)
            p1 = (cj1[0] - X) ** 2 + (cj1[1] - Z) ** 2
            if p1 < phi or p1 <= floor:
                th, L0, cj = th1, L1, cj1
                accepted = True
                break
            step *= 0.5
        if not accepted:
            break
        if abs(step * dth) <= 1e-15 and abs(step * dL) <= 1e-15 * L0:
            H = tau * math.cos(th)
            VB = tau * math.sin(th)
            Xc, Zc = _closure_jac(H, VB, L0, w, EA)[:2]
            if math.hypot(Xc - X, Zc - Z) <= 1e-11 * c:
                return H, VB, L0, True
            break
    H = tau * math.cos(th)
    VB = tau * math.sin(th)
    Xc, Zc = _closure_jac(H, VB, L0, w, EA)[:2]
    if math.hypot(Xc - X, Zc - Z) <= 1e-11 * c:
        return H, VB, L0, True
    return nan, nan, nan, False


@njit
def _span(px, py, pz, Rb, A, up, cw, lengths):
    """Per-cable chord length, span X, height Z and horizontal unit vector; False if a length is 0."""
    ok = True
    for i in range(A.shape[0]):
        lx = A[i, 0] - px - Rb[i, 0]
        ly = A[i, 1] - py - Rb[i, 1]
        lz = A[i, 2] - pz - Rb[i, 2]
        li = math.sqrt(lx * lx + ly * ly + lz * lz)
        lengths[i] = li
        if li <= 1e-12:
            ok = False
        Z = lx * up[0] + ly * up[1] + lz * up[2]
        hx = lx - Z * up[0]
        hy = ly - Z * up[1]
        hz = lz - Z * up[2]
        X = math.sqrt(hx * hx + hy * hy + hz * hz)
        cw[i, _X] = X
        cw[i, _Z] = Z
        if X > 1e-14 * li:
            cw[i, _UX], cw[i, _UY], cw[i, _UZ] = hx / X, hy / X, hz / X
        else:
            cw[i, _X] = 0.0
            cw[i, _UX], cw[i, _UY], cw[i, _UZ] = 0.0, 0.0, 0.0
        cw[i, _TH] = math.nan
        cw[i, _L0] = math.nan
        cw[i, _TM] = math.nan
        cw[i, _TAU] = math.nan
        cw[i, _TP] = math.nan
    return ok


@njit
def _least_shape(i, X, Z, w, EA, cw):
    """Cable i's least tension (:func:`least_tension`), computed once per pose into ``cw``."""
    if math.isnan(cw[i, _TM]):
        cw[i, _TM], cw[i, _HM], cw[i, _VM], cw[i, _LM] = least_tension(X, Z, w, EA)
    return cw[i, _TM]


@njit
def _secant_start(i, tau, cw):
    """A start (th, L0) for cable i at tension tau: the last shape, moved along the secant
    through the last two shapes when they are at distinct tensions and tau is not far off."""
    th, L0 = cw[i, _TH], cw[i, _L0]
    d = cw[i, _TAU] - cw[i, _TP]
    if d != 0.0 and math.isfinite(d) and math.isfinite(cw[i, _THP]) and math.isfinite(cw[i, _LP]):
        s = (tau - cw[i, _TAU]) / d
        if abs(s) <= 4.0:
            th1 = th + s * (th - cw[i, _THP])
            L1 = L0 + s * (L0 - cw[i, _LP])
            if abs(th1) < 1.5 and L1 > 0.0:
                return th1, L1
    return th, L0


@njit
def _slack_column(i, X, Z, up, tmin, tmax, Rb, rows, cw, W):
    """A slack cable: no force, shape and length undetermined; column along the chord."""
    cw[i, _TH] = math.nan
    cw[i, _L0] = math.nan
    cw[i, _TAU] = math.nan
    cw[i, _H] = 0.0
    cw[i, _VB] = 0.0
    cw[i, _TA] = math.nan
    cw[i, _LO] = tmin[i]
    cw[i, _HI] = tmax[i]
    c = math.hypot(X, Z)
    if X > 0.0:
        dx = (X * cw[i, _UX] + Z * up[0]) / c
        dy = (X * cw[i, _UY] + Z * up[1]) / c
        dz = (X * cw[i, _UZ] + Z * up[2]) / c
    else:
        s = 1.0 if Z > 0.0 else -1.0
        dx, dy, dz = s * up[0], s * up[1], s * up[2]
    fill_column(W, i, rows, dx, dy, dz, Rb[i, 0], Rb[i, 1], Rb[i, 2])


@njit
def shapes_for(t, Rb, up, w, EA, tmin, tmax, rows, cw, W, maxit):
    """Cable shapes for effector-end tensions ``t`` (m) [N]: the structure matrix ``W``
    from the end-force directions, and in ``cw`` each cable's (th, L0, H, VB), the
    bounds shifted to hold along the whole cable (lo, hi) and the outlet tension.
    ``cw`` must hold the spans from :func:`_span` (and the previous th, L0 as a start).

    A heavy cable cannot pull with less than its least tension (:func:`least_tension`):
    asked for less, it takes that least-tension shape, and from then on its lower bound
    is at least that tension.  Only a weightless cable, or one hanging straight down
    from its outlet, is slack at (near) zero tension.
    Returns 1; 2 when a cable was raised to its least tension (``t`` is then not
    consistent with ``W``); 0 when a cable has no shape.
    """
    tscale = 1.0
    for i in range(t.shape[0]):
        tscale = max(tscale, abs(t[i]))
    out = 1
    for i in range(t.shape[0]):
        X = cw[i, _X]
        Z = cw[i, _Z]
        can_slack = w[i] == 0.0 or (X <= 0.0 and Z > 0.0)
        if t[i] <= SLACK * tscale and can_slack:
            _slack_column(i, X, Z, up, tmin, tmax, Rb, rows, cw, W)
            continue
        tau = t[i]
        ok = False
        if tau > 0.0:
            th0, L00 = _secant_start(i, tau, cw)
            H, VB, L0, ok = cable_for_tension(X, Z, tau, w[i], EA[i], th0, L00, maxit)
        cw[i, _TP], cw[i, _THP], cw[i, _LP] = cw[i, _TAU], cw[i, _TH], cw[i, _L0]
        cw[i, _TAU] = tau if ok else math.nan
        if not ok:
            tm = _least_shape(i, X, Z, w[i], EA[i], cw)
            if not (tau <= tm * (1.0 + 1e-12)):
                return 0  # above the least tension (or NaN), and yet no shape
            if tau < tm * (1.0 - 1e-12):
                out = 2
            tau, H, VB, L0 = tm, cw[i, _HM], cw[i, _VM], cw[i, _LM]
        th = math.atan2(VB, H)
        cw[i, _TH] = th
        cw[i, _L0] = L0
        cw[i, _H] = H
        cw[i, _VB] = VB
        VA = VB + w[i] * L0
        TA = math.hypot(H, VA)
        tmax_along = max(TA, tau)
        tmin_along = H if (VB < 0.0 < VA) else min(TA, tau)
        cw[i, _TA] = TA
        cw[i, _LO] = tmin[i] + (tau - tmin_along)
        if not math.isnan(cw[i, _TM]):
            cw[i, _LO] = max(cw[i, _LO], cw[i, _TM])
        cw[i, _HI] = tmax[i] - (tmax_along - tau)
        if X > 0.0:
            ch = H / tau
            sv = VB / tau
            dx = ch * cw[i, _UX] + sv * up[0]
            dy = ch * cw[i, _UY] + sv * up[1]
            dz = ch * cw[i, _UZ] + sv * up[2]
        else:
            s = 1.0 if VB > 0.0 else -1.0
            dx, dy, dz = s * up[0], s * up[1], s * up[2]
        fill_column(W, i, rows, dx, dy, dz, Rb[i, 0], Rb[i, 1], Rb[i, 2])
    return out


@njit
def _straight_columns(Rb, A, px, py, pz, rows, W):
    for i in range(A.shape[0]):
        lx = A[i, 0] - px - Rb[i, 0]
        ly = A[i, 1] - py - Rb[i, 1]
        lz = A[i, 2] - pz - Rb[i, 2]
        li = math.sqrt(lx * lx + ly * ly + lz * lz)
        fill_column(W, i, rows, lx / li, ly / li, lz / li, Rb[i, 0], Rb[i, 1], Rb[i, 2])


@njit
def _balanced(W, t, w0):
    """Whether W t = w0 to SAG_TOL (1 + |w0| + max t) [N]."""
    n, m = W.shape
    wn = 0.0
    for k in range(n):
        wn = max(wn, abs(w0[k]))
    for i in range(m):
        wn = max(wn, abs(t[i]))
    for k in range(n):
        acc = 0.0
        for i in range(m):
            acc += W[k, i] * t[i]
        if abs(acc - w0[k]) > SAG_TOL * (1.0 + wn):
            return False
    return True


@njit
def _relax(g, x, cw, omega, again, tscale):
    """Aitken's dynamic relaxation of the fixed point x -> g (Irons & Tuck): the next iterate
    x + omega (g - x), written into ``g``, with omega = -omega' r'.(r - r') / |r - r'|^2 from
    this residual r = g - x and the previous one r' (``cw``), kept within [1/16, 16].  Plain
    steps (omega = 1) when ``again`` is False (first step, or a cable was just raised to its
    least tension) and once the residual is below 1e-11 ``tscale``, so that convergence is
    always judged on a plain step.  Returns omega."""
    num = 0.0
    den = 0.0
    rmax = 0.0
    for i in range(g.shape[0]):
        r = g[i] - x[i]
        dr = r - cw[i, _RP]
        num += cw[i, _RP] * dr
        den += dr * dr
        rmax = max(rmax, abs(r))
        cw[i, _RP] = r
    if not again or not (den > 0.0) or rmax <= 1e-11 * tscale:
        return 1.0
    omega = min(max(-omega * num / den, 0.0625), 16.0)
    for i in range(g.shape[0]):
        cw[i, _GP] = g[i]
        g[i] = x[i] + omega * cw[i, _RP]
    return omega


@njit
def _retreat(t, cw):
    """A relaxed iterate overshot (no shape, or no tensions within the bounds): back to the
    unrelaxed one, and plain steps from there on.  Returns (plain, relax) = (True, False)."""
    for i in range(t.shape[0]):
        t[i] = cw[i, _GP]
    return True, False


@njit
def _no_tensions(cw, lo):
    """The status of a pose whose bounds admit no tensions: :data:`SAG_NO_CATENARY` when a
    cable's lower bound is its least tension, else :data:`SAG_NO_TENSIONS`."""
    for i in range(lo.shape[0]):
        if lo[i] == cw[i, _TM]:
            return SAG_NO_CATENARY
    return SAG_NO_TENSIONS


@njit
def _distribute(W, w0, lo, hi, inf_hi, t, scr):
    """Minimum-norm tensions under (lo, hi); failing that under (lo, inf). Returns 2, 1 or 0."""
    if min_norm_tensions(W, w0, lo, hi, t, scr):
        return 2
    if min_norm_tensions(W, w0, lo, inf_hi, t, scr):
        return 1
    return 0


@njit
def sag_pose(px, py, pz, Rb, A, rows, up, w, EA, wreq, tmin, tmax, combos, kind, maxit,
             t, outlet, L0, sag, lengths, W, cw, lo, hi, inf_hi, tq, scr):
    """One pose with sagging cables: (status, feasible, margin, iterations).

    Inputs as :func:`cdpr_design.kernels.sweep.sweep_grid` plus ``up`` (3,)
    (unit vector against gravity), ``w`` (m,) [N/m] cable weight per length
    (0: a straight elastic cable) and ``EA`` (m,) [N].  Outputs: ``t``
    effector-end tensions [N], ``outlet`` outlet tensions [N], ``L0``
    unstretched lengths [m], ``sag`` largest distance from the chord [m] (all
    NaN unless the pose is feasible), ``lengths`` chord lengths [m].  ``W``,
    ``cw``, ``lo``, ``hi``, ``inf_hi`` (all inf), ``tq``, ``scr`` are scratch.
    A slack cable (tension at or below :data:`SLACK` of the largest, where its
    lower bound is 0) pulls along its chord with no force; its outlet tension,
    unstretched length and sag are NaN (undetermined) in a feasible pose.
    The margin is the capacity margin of the converged structure matrix under
    the shifted bounds (NaN unless the status is :data:`SAG_OK`).
    """
    m = A.shape[0]
    for i in range(m):
        t[i] = math.nan
        outlet[i] = math.nan
        L0[i] = math.nan
        sag[i] = math.nan
    if not _span(px, py, pz, Rb, A, up, cw, lengths):
        return SAG_SINGULAR, False, math.nan, 0
    _straight_columns(Rb, A, px, py, pz, rows, W)
    bounded = _distribute(W, wreq[0], tmin, tmax, inf_hi, tq, scr)
    if bounded == 0:
        return SAG_NO_TENSIONS, False, math.nan, 0
    tprev = outlet  # scratch until the end
    tscale = 1.0
    for i in range(m):
        tscale = max(tscale, abs(tq[i]))
    converged = False
    it = 0
    omega = 1.0
    plain = True  # tq is the distribution of the previous shapes, not a relaxed iterate
    relax = True
    while it < maxit:
        it += 1
        fit = shapes_for(tq, Rb, up, w, EA, tmin, tmax, rows, cw, W, 60)
        if fit == 0 and not plain:
            plain, relax = _retreat(tq, cw)
            continue
        if fit == 0:
            outlet[:] = math.nan
            return SAG_NO_CATENARY, False, math.nan, it
        if it > 1 and fit == 1 and plain and _balanced(W, tq, wreq[0]):
            dt = 0.0
            for i in range(m):
                dt = max(dt, abs(tq[i] - tprev[i]))
            if dt <= 1e-9 * tscale:
                converged = True
                break
        for i in range(m):
            lo[i] = cw[i, _LO]
            hi[i] = cw[i, _HI]
            tprev[i] = tq[i]
        bounded = _distribute(W, wreq[0], lo, hi, inf_hi, tq, scr)
        if bounded == 0 and not plain:
            plain, relax = _retreat(tq, cw)
            continue
        if bounded == 0:
            outlet[:] = math.nan
            return _no_tensions(cw, lo), False, math.nan, it
        omega = _relax(tq, tprev, cw, omega, relax and it > 1 and fit == 1, tscale)
        plain = omega == 1.0
    for i in range(m):
        outlet[i] = math.nan
    if not converged:
        return SAG_NOT_CONVERGED, False, math.nan, it
    for i in range(m):
        lo[i] = cw[i, _LO]
        hi[i] = cw[i, _HI]
    n = W.shape[0]
    if m == n:
        feasible, margin = eval_pose(W, wreq, lo, hi, combos, kind, t)
    else:
        feasible, margin = eval_general(W, wreq, lo, hi, combos, kind, t, scr)
    feasible = feasible and bounded == 2
    for i in range(m):
        t[i] = tq[i] if feasible else math.nan
        if feasible and not math.isnan(cw[i, _L0]):
            outlet[i] = cw[i, _TA]
            L0[i] = cw[i, _L0]
            sag[i] = catenary_sag(cw[i, _H], cw[i, _VB], cw[i, _L0], w[i], EA[i])[0]
    return SAG_OK, feasible, margin + 0.0, it


@njit
def make_sag_scratch(n, m, nv):
    """Scratch for :func:`sag_pose`: (W, cw, lo, hi, inf_hi, tq, scr)."""
    inf_hi = np.full(m, np.inf)
    return (np.empty((n, m)), np.empty((m, NCW)), np.empty(m), np.empty(m), inf_hi, np.empty(m),
            make_scratch(n, m, nv))


@njit_parallel
def sweep_grid_sagging(start, count, lower, step, shape, Rb, A, rows, up, w, EA, wreq, tmin, tmax,
                       combos, kind, maxit, feasible, margin, tensions, lengths, outlet, L0, sag, status):
    """:func:`cdpr_design.kernels.sweep.sweep_grid` with sagging cables (:func:`sag_pose`).

    Extra outputs (count, m): ``outlet`` tensions [N], unstretched lengths
    ``L0`` [m], ``sag`` [m]; ``status`` (count,) int8.  Every pose starts from
    its own straight-cable solution, so rows do not depend on the chunking.
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
        Wb, cw, lo, hi, inf_hi, tq, scr = make_sag_scratch(n, m, wreq.shape[0])
        t = np.empty(m)
        ta = np.empty(m)
        l0 = np.empty(m)
        sg = np.empty(m)
        L = np.empty(m)
        k0 = b * bsize
        k1 = min(count, k0 + bsize)
        for k in range(k0, k1):
            idx = start + k
            iz = idx % nz
            r = idx // nz
            iy = r % ny
            ix = r // ny
            st, f, mg, _ = sag_pose(lower[0] + ix * step[0], lower[1] + iy * step[1], lower[2] + iz * step[2],
                                    Rb, A, rows, up, w, EA, wreq, tmin, tmax, combos, kind, maxit,
                                    t, ta, l0, sg, L, Wb, cw, lo, hi, inf_hi, tq, scr)
            status[k] = st
            feasible[k] = 1 if f else 0
            margin[k] = mg
            for i in range(m):
                tensions[k, i] = t[i]
                lengths[k, i] = L[i]
                outlet[k, i] = ta[i]
                L0[k, i] = l0[i]
                sag[k, i] = sg[i]
