"""The elastic catenary's inverse problem: the end forces of a cable of given length spanning given ends.

Conventions, model and references in :mod:`cdpr_design.kernels.catenary` (X horizontal span,
Z height of the outlet A above the attachment B [m], L0 unstretched length [m], w weight per
length [N/m], EA [N]; H, VB the end forces at B [N]).

The problem is solved by a damped Newton method on the closure equations with the analytic
Jacobian, started from the straight elastic cable or the inextensible catenary (the
Peyrot-Goulois shape parameter), and falls back to a nested, bracketed 1-D solve that cannot
fail on a problem that has a solution: for fixed H the height is increasing in VB, and along
that curve the span is increasing in H (the flexibility matrix d(X, Z)/d(H, VB) is symmetric
positive definite - it is the Hessian of the cable's complementary energy).
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.kernels._jit import njit, njit_folded
from cdpr_design.kernels.catenary import catenary_ends, closure_jac
from cdpr_design.kernels.parallel import run_blocks
from cdpr_design.kernels.scalar import hypot

#: Status codes of :func:`catenary_inverse`.
CAT_CONVERGED = 0
#: Weightless cable (w = 0) whose chord is not longer than L0: it is slack,
#: the end forces are exactly zero and its shape is undetermined.
CAT_SLACK = 1
#: The iterations stopped before convergence; H and VB are NaN.
CAT_NOT_CONVERGED = 2
#: No solution: invalid input (non-finite, L0 <= 0, w < 0, EA <= 0, X < 0),
#: an inextensible cable shorter than (or exactly as long as) its chord, or a
#: taut vertical inextensible cable (tension indeterminate).  H and VB are NaN.
CAT_NO_SOLUTION = 3

_EPS = 2.220446049250313e-16


@njit_folded
def _log_sinhc(lam):
    """ln(sinh(lam)/lam) for lam >= 0 and its derivative coth(lam) - 1/lam."""
    if lam < 1e-3:
        l2 = lam * lam
        return l2 / 6.0 - l2 * l2 / 180.0, lam / 3.0 - l2 * lam / 45.0
    if lam < 20.0:
        return math.log(math.sinh(lam) / lam), 1.0 / math.tanh(lam) - 1.0 / lam
    return lam - math.log(2.0 * lam) + math.log1p(-math.exp(-2.0 * lam)), 1.0 / math.tanh(lam) - 1.0 / lam


@njit_folded
def _shape_parameter(rho):
    """lam > 0 with sinh(lam)/lam = rho (rho > 1): the inextensible catenary's
    half span over its parameter, lam = w X / (2 H)."""
    q = math.log(rho)
    if q < 1.0:
        lam = math.sqrt(6.0 * q)
    else:
        lam = q + math.log(2.0 * (q + 1.0))
    for _ in range(60):
        f, df = _log_sinhc(lam)
        if df <= 0.0:
            break
        step = (f - q) / df
        lam_new = lam - step
        if lam_new <= 0.0:
            lam_new = 0.5 * lam
        if abs(lam_new - lam) <= 1e-14 * lam:
            lam = lam_new
            break
        lam = lam_new
    return lam


@njit_folded
def _start_catenary(X, Z, L0, w, EA, c):
    """Start from the inextensible catenary of length L0 (1 + mean tension/EA)."""
    Leff = L0
    H = math.nan
    VB = math.nan
    for _ in range(4):
        Lc = max(Leff, c * (1.0 + 1e-6))
        rho = math.sqrt((Lc - Z) * (Lc + Z)) / X
        if not rho > 1.0 + 1e-12:
            rho = 1.0 + 1e-12
        lam = _shape_parameter(rho)
        H = w * X / (2.0 * lam)
        VB = 0.5 * (w * Z / math.tanh(lam) - w * L0)
        Tm = 0.5 * (hypot(H, VB) + hypot(H, VB + w * L0))
        Lnew = L0 * (1.0 + Tm / EA)
        if abs(Lnew - Leff) <= 1e-9 * Leff:
            break
        Leff = Lnew
    return H, VB


@njit_folded
def _residual(H, VB, X, Z, L0, w, EA):
    Xc, Zc = catenary_ends(H, VB, L0, w, EA)
    return Xc - X, Zc - Z


@njit
def _solve_vb(H, Z, L0, w, EA, VB0, scale_f):
    """VB with Z(H, VB) = Z at fixed H > 0 (Z increasing in VB): bracket, then
    Newton safeguarded by bisection.  Returns (VB, ok, iterations)."""
    lo = VB0
    hi = VB0
    step = max(abs(VB0), scale_f)
    it = 0
    _, zlo = catenary_ends(H, lo, L0, w, EA)
    while zlo > Z:
        hi = lo
        lo = lo - step
        step *= 2.0
        _, zlo = catenary_ends(H, lo, L0, w, EA)
        it += 1
        if it > 300 or not math.isfinite(lo):
            return math.nan, False, it
    _, zhi = catenary_ends(H, hi, L0, w, EA)
    while zhi < Z:
        lo = hi
        hi = hi + step
        step *= 2.0
        _, zhi = catenary_ends(H, hi, L0, w, EA)
        it += 1
        if it > 300 or not math.isfinite(hi):
            return math.nan, False, it
    v = 0.5 * (lo + hi)
    for _ in range(300):
        it += 1
        _, zv, _, _, _, d = closure_jac(H, v, L0, w, EA)
        r = zv - Z
        if r == 0.0:
            return v, True, it
        if r > 0.0:
            hi = v
        else:
            lo = v
        vn = 0.5 * (lo + hi)
        if d > 0.0 and math.isfinite(d):
            vn = v - r / d
            if not (lo < vn < hi):
                vn = 0.5 * (lo + hi)
        width = 4.0 * _EPS * (abs(v) + scale_f)
        if abs(vn - v) <= width or hi - lo <= width:
            return vn, True, it
        v = vn
    return v, False, it


@njit_folded
def _fallback(X, Z, L0, w, EA, H0, VB0, scale_f, floor, maxit):
    """Nested bracketed solve: outer on y = ln H (the span is increasing in H
    along the curve Z(H, VB(H)) = Z), inner :func:`_solve_vb`.  ``maxit`` bounds
    the outer steps (bracketing and refinement).  Returns (H, VB, ok, outer
    steps).  ``floor`` [m]: span residual at round-off (VB is only known to the
    resolution of Z, so the span cannot be closed below that)."""
    ln4 = 1.3862943611198906
    it = 0
    vb, ok, _ = _solve_vb(H0, Z, L0, w, EA, VB0, scale_f)
    if not ok:
        return math.nan, math.nan, False, it
    gx, _ = catenary_ends(H0, vb, L0, w, EA)
    g = gx - X
    if g == 0.0:
        return H0, vb, True, it
    # bracket the root in y: one end moves by ln 4 a step (down while the span is too long, up
    # while too short), the end it leaves is the bracket's other end
    down = g > 0.0
    y, v = math.log(H0), vb  # the moving end
    yp, vp = y, v  # the end it left
    while g > 0.0 if down else g < 0.0:
        if it >= maxit or (y < -700.0 if down else y > 700.0):
            return math.nan, math.nan, False, it
        it += 1
        yp, vp = y, v
        y += -ln4 if down else ln4
        vb, ok, _ = _solve_vb(math.exp(y), Z, L0, w, EA, v, scale_f)
        if not ok:
            return math.nan, math.nan, False, it
        v = vb
        gx, _ = catenary_ends(math.exp(y), vb, L0, w, EA)
        g = gx - X
    if g == 0.0:
        return math.exp(y), v, True, it
    ylo, vlo, yhi, vhi = (y, v, yp, vp) if down else (yp, vp, y, v)
    # safeguarded Newton in y
    y = 0.5 * (ylo + yhi)
    vb = 0.5 * (vlo + vhi)
    while it < maxit:
        it += 1
        H = math.exp(y)
        vb, ok, _ = _solve_vb(H, Z, L0, w, EA, vb, scale_f)
        if not ok:
            return math.nan, math.nan, False, it
        gx, _, a, b, c, d = closure_jac(H, vb, L0, w, EA)
        g = gx - X
        if abs(g) <= floor:
            return H, vb, True, it
        if g > 0.0:
            yhi = y
        else:
            ylo = y
        yn = 0.5 * (ylo + yhi)
        if d > 0.0:
            dg = H * (a - b * c / d)  # dX/dy along Z = const: the Schur complement
            if dg > 0.0 and math.isfinite(dg):
                yn = y - g / dg
                if not (ylo < yn < yhi):
                    yn = 0.5 * (ylo + yhi)
        width = 4.0 * _EPS * max(1.0, abs(y))
        if abs(yn - y) <= width or yhi - ylo <= width:
            H = math.exp(yn)
            vb, ok, _ = _solve_vb(H, Z, L0, w, EA, vb, scale_f)
            return H, vb, ok, it
        y = yn
    return math.nan, math.nan, False, it


@njit_folded
def _vertical(Z, L0, w, EA):
    """H = 0: VB solving the piecewise-linear height of a vertical cable.

    s = VA + VB; Z = L0 + L0 s/(2EA) if VB >= 0 (hanging from A), -L0 + L0 s/(2EA)
    if VA <= 0 (hanging from B), s/w + L0 s/(2EA) in between (folded at its
    lowest point).  Returns (VB, status).
    """
    wl = w * L0
    k = L0 / (2.0 * EA)
    # heights at the two kinks s = +wl and s = -wl
    z_hi = L0 + k * wl
    z_lo = -L0 - k * wl
    if Z >= z_hi:
        if k == 0.0:
            return math.nan, CAT_NO_SOLUTION  # taut inextensible: tension indeterminate
        s = (Z - L0) / k
    elif Z <= z_lo:
        if k == 0.0:
            return math.nan, CAT_NO_SOLUTION
        s = (Z + L0) / k
    else:
        s = Z / (1.0 / w + k)
    return 0.5 * (s - wl), CAT_CONVERGED


@njit
def catenary_inverse(X, Z, L0, w, EA, H0, VB0, tol, maxit):
    """End forces (H, VB) [N] of a cable of unstretched length L0 spanning X, Z.

    ``X`` [m] >= 0 horizontal span, ``Z`` [m] height of the outlet A above the
    attachment B (any sign), ``L0`` [m], ``w`` [N/m], ``EA`` [N] (``inf`` for an
    inextensible cable) as in :func:`catenary_ends`.  ``H0``, ``VB0``: a start
    (e.g. the previous pose's solution); pass NaN (or H0 <= 0) for the built-in
    start.  ``tol``: relative force tolerance (e.g. 1e-12); ``maxit``: Newton
    iterations allowed, and as many outer steps of the fallback (100 is ample).

    Returns ``(H, VB, status, iterations)``; status is :data:`CAT_CONVERGED`,
    :data:`CAT_SLACK` (weightless cable with chord <= L0: zero forces),
    :data:`CAT_NOT_CONVERGED` or :data:`CAT_NO_SOLUTION`; on the last two H and
    VB are NaN, never an unconverged value.

    Method: Newton on the closure residual with the analytic Jacobian and an
    Armijo backtracking line search on its squared norm, H kept positive; start
    from the straight elastic cable (chord longer than L0) or the inextensible
    catenary of length L0 (1 + T/EA) (Peyrot-Goulois shape parameter), whichever
    closes better.  Converged when a full Newton step is below ``tol`` times the
    end forces, or the residual is at round-off.  If the line search stalls or
    ``maxit`` is reached, a nested bracketed 1-D solve takes over (see the
    module docstring); its result is checked against the closure too.
    """
    nan = math.nan
    if not (math.isfinite(X) and math.isfinite(Z) and math.isfinite(L0) and math.isfinite(w)):
        return nan, nan, CAT_NO_SOLUTION, 0
    if not (L0 > 0.0 and w >= 0.0 and EA > 0.0 and X >= 0.0) or math.isnan(EA):
        return nan, nan, CAT_NO_SOLUTION, 0
    if not tol > 0.0:
        tol = 1e-12
    c = hypot(X, Z)
    inextensible = math.isinf(EA)
    # weightless: straight elastic cable (or slack)
    if w == 0.0:
        if c <= L0:
            return 0.0, 0.0, CAT_SLACK, 0
        if inextensible:
            return nan, nan, CAT_NO_SOLUTION, 0
        T = EA * (c / L0 - 1.0)
        return T * (X / c), T * (Z / c), CAT_CONVERGED, 0
    if inextensible and c >= L0:
        return nan, nan, CAT_NO_SOLUTION, 0
    if X == 0.0:
        vb, st = _vertical(Z, L0, w, EA)
        if st != CAT_CONVERGED:
            return nan, nan, st, 0
        return 0.0, vb, st, 0
    wl = w * L0
    # length scale for the round-off floor of the residual
    scale_l = c + L0
    # start
    if math.isfinite(H0) and math.isfinite(VB0) and H0 > 0.0:
        H = H0
        VB = VB0
        rx, rz = _residual(H, VB, X, Z, L0, w, EA)
        phi = rx * rx + rz * rz
    else:
        H = nan
        VB = nan
        phi = math.inf
        if not inextensible and c > L0:
            T = EA * (c / L0 - 1.0)
            h1 = T * X / c
            v1 = T * Z / c - 0.5 * wl
            if h1 > 0.0:
                rx, rz = _residual(h1, v1, X, Z, L0, w, EA)
                p1 = rx * rx + rz * rz
                if p1 < phi:
                    H, VB, phi = h1, v1, p1
        h2, v2 = _start_catenary(X, Z, L0, w, EA, c)
        if h2 > 0.0 and math.isfinite(h2) and math.isfinite(v2):
            rx, rz = _residual(h2, v2, X, Z, L0, w, EA)
            p2 = rx * rx + rz * rz
            if p2 < phi or not math.isfinite(phi):
                H, VB, phi = h2, v2, p2
        if not (H > 0.0 and math.isfinite(phi)):
            H = max(wl, 1e-300)
            VB = 0.0
            rx, rz = _residual(H, VB, X, Z, L0, w, EA)
            phi = rx * rx + rz * rz
    it = 0
    converged = False
    floor = (16.0 * _EPS * scale_l) ** 2
    while it < maxit:
        it += 1
        Xc, Zc, a, b, cc, d = closure_jac(H, VB, L0, w, EA)
        rx = Xc - X
        rz = Zc - Z
        phi = rx * rx + rz * rz
        det = a * d - b * cc
        if not (det > 0.0 and math.isfinite(det)):
            break
        dH = -(d * rx - b * rz) / det
        dV = -(-cc * rx + a * rz) / det
        fscale = H + abs(VB) + abs(VB + wl)
        small = abs(dH) + abs(dV) <= tol * fscale
        if phi == 0.0:
            converged = True
            break
        if small or phi <= floor:
            if H + dH > 0.0:
                H += dH
                VB += dV
            converged = True
            break
        # keep H > 0: shrink by at most a factor 4 per step
        alpha = 1.0
        if H + dH < 0.25 * H:
            alpha = 0.75 * H / (-dH)
        # Deuflhard's natural monotonicity test: the simplified Newton correction
        # -J^-1 r(trial) (same J) must shrink; affine invariant, so the mixed
        # scales of the span and height residuals do not matter.
        nrm = abs(dH) + abs(dV)
        accepted = False
        for _ in range(40):
            hn = H + alpha * dH
            vn = VB + alpha * dV
            rxn, rzn = _residual(hn, vn, X, Z, L0, w, EA)
            sH = -(d * rxn - b * rzn) / det
            sV = -(-cc * rxn + a * rzn) / det
            if abs(sH) + abs(sV) <= (1.0 - 0.25 * alpha) * nrm or rxn * rxn + rzn * rzn <= floor:
                accepted = True  # (or the trial closes to round-off: the test is noise there)
                break
            alpha *= 0.5
        if not accepted:
            break
        H = hn
        VB = vn
    if converged:
        rx, rz = _residual(H, VB, X, Z, L0, w, EA)
        if hypot(rx, rz) <= 1e-8 * scale_l:
            return H, VB, CAT_CONVERGED, it
    # fallback: nested bracketed solve from the best point so far
    if not (H > 0.0 and math.isfinite(H) and math.isfinite(VB)):
        H = max(wl, 1e-300)
        VB = 0.0
    h, v, ok, k = _fallback(X, Z, L0, w, EA, H, VB, wl + H + abs(VB), 16.0 * _EPS * scale_l, maxit)
    it += k
    if ok and h > 0.0:
        rx, rz = _residual(h, v, X, Z, L0, w, EA)
        if hypot(rx, rz) <= 1e-8 * scale_l:
            return h, v, CAT_CONVERGED, it
    return nan, nan, CAT_NOT_CONVERGED, it



# ---------------------------------------------------------------------------
# batched
# ---------------------------------------------------------------------------

def catenary_inverse_batch(X, Z, L0, w, EA, H0, VB0, tol, maxit):
    """:func:`catenary_inverse` over n cables (arrays of equal length n; ``H0``,
    ``VB0`` may hold NaN for the built-in start), in blocks on threads.  Returns
    (H, VB, status, iterations) as arrays (status int8, iterations int32)."""
    n = X.shape[0]
    H, VB, status, iters = np.empty(n), np.empty(n), np.empty(n, dtype=np.int8), np.empty(n, dtype=np.int32)
    run_blocks(_inverse_block, n, X, Z, L0, w, EA, H0, VB0, tol, maxit, H, VB, status, iters, grain=256)
    return H, VB, status, iters


@njit
def _inverse_block(k0, k1, X, Z, L0, w, EA, H0, VB0, tol, maxit, H, VB, status, iters):
    for i in range(k0, k1):
        H[i], VB[i], status[i], iters[i] = catenary_inverse(X[i], Z[i], L0[i], w[i], EA[i], H0[i], VB0[i], tol,
                                                            maxit)


