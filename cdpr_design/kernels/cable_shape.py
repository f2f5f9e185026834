"""One heavy, elastic cable at a given tension: its shape, and the least tension it can have.

The building blocks of the robot-level sagging statics
(:mod:`cdpr_design.kernels.sagging`), on top of the elastic catenary of
:mod:`cdpr_design.kernels.catenary` (conventions there: X horizontal span,
Z height of the outlet above the attachment [m], w weight per length [N/m],
EA [N]).
"""

from __future__ import annotations

import math

from cdpr_design.kernels._jit import njit, njit_folded
from cdpr_design.kernels.catenary import closure_jac
from cdpr_design.kernels.catenary_inv import CAT_CONVERGED, catenary_inverse
from cdpr_design.kernels.scalar import hypot


@njit_folded
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
    a, b, c, d = closure_jac(H, VB, L0, w, EA)[2:]
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
    c = hypot(X, Z)
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
            return hypot(h, v), h, v, math.exp(x)
    ta = hypot(ha, va)
    tb = hypot(hb, vb)
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
    c = hypot(X, Z)
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
    cj = closure_jac(tau * math.cos(th), tau * math.sin(th), L0, w, EA)
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
        k = 1.0 / hypot(H, VA) + 1.0 / EA
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
            cj1 = closure_jac(tau * math.cos(th1), tau * math.sin(th1), L1, w, EA)
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
            Xc, Zc = closure_jac(H, VB, L0, w, EA)[:2]
            if hypot(Xc - X, Zc - Z) <= 1e-11 * c:
                return H, VB, L0, True
            break
    H = tau * math.cos(th)
    VB = tau * math.sin(th)
    Xc, Zc = closure_jac(H, VB, L0, w, EA)[:2]
    if hypot(Xc - X, Zc - Z) <= 1e-11 * c:
        return H, VB, L0, True
    return nan, nan, nan, False
