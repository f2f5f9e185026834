"""Elastic catenary kernels: one sagging, stretching cable in its vertical plane.

Model: the elastic catenary of Irvine (1981), as used for cable
robots by Kozak, Zhou, Wang (2006) and Gouttefarde, Collard, Riehl, Baradat
(2015); equation numbers are not quoted here.  A cable of unstretched length ``L0``
[m], weight per unstretched length ``w`` [N/m] (mass per length times g) and
axial stiffness ``EA`` [N] hangs between its outlet A (frame/winch side) and its
attachment B (effector).  In the vertical plane through A and B, x is horizontal
from B towards A and z points up.  The unstretched arc length s runs from B
(s = 0) to A (s = L0).  The end forces are

* ``H`` >= 0 [N]: horizontal tension component, the same all along the cable;
* ``VB`` [N]: vertical component at B, positive when the cable pulls the
  effector up; ``V(s) = VB + w s`` along the cable and ``VA = VB + w L0`` at A
  (positive when the cable pulls the outlet down).

Tension ``T(s) = sqrt(H^2 + V(s)^2)``; it is largest at an end (at A when
``VA >= |VB|``).  With X the horizontal span and Z the height of A above B:

    X = H/w [asinh(VA/H) - asinh(VB/H)] + H L0/EA
    Z = H/w [sqrt(1 + (VA/H)^2) - sqrt(1 + (VB/H)^2)] + (VA L0 - w L0^2/2)/EA

Everything here is written without the 1/w of these textbook forms, so that
``w -> 0`` gives the straight elastic cable smoothly (``w = 0`` exactly is
allowed), and ``H = 0`` is the vertical cable (hanging, or folded when VB < 0 <
VA).  ``EA = inf`` is the inextensible catenary.

The inverse problem (span and height given, end forces wanted) is
:mod:`cdpr_design.kernels.catenary_inv`.

References
----------
H. M. Irvine, *Cable Structures*, MIT Press, 1981.
K. Kozak, Q. Zhou, J. Wang, "Static analysis of cable-driven manipulators with
non-negligible cable mass", IEEE Trans. Robotics 22(3), 2006.
M. Gouttefarde, J.-F. Collard, N. Riehl, C. Baradat, "Simplified static
analysis of large-dimension parallel cable-driven robots", IEEE Trans.
Robotics 31(1), 2015.
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.kernels._jit import njit, njit_folded
from cdpr_design.kernels.parallel import run_blocks
from cdpr_design.kernels.scalar import hypot

# 12-point Gauss-Legendre rule on [-1, 1] (for the short-interval mean in the Jacobian).
_GL_X, _GL_W = np.polynomial.legendre.leggauss(12)
_GL_X = np.ascontiguousarray(_GL_X)
_GL_W = np.ascontiguousarray(_GL_W)


@njit_folded
def _asinhc(u):
    """asinh(u) / u, with the value 1 at u = 0."""
    if abs(u) < 1e-3:
        u2 = u * u
        return 1.0 - u2 / 6.0 + 3.0 * u2 * u2 / 40.0 - 5.0 * u2 * u2 * u2 / 112.0
    return math.asinh(u) / u


@njit_folded
def _ratio(v, t):
    """v / t with 0/0 -> 0 (sign of a vertical component at zero tension)."""
    if t > 0.0:
        return v / t
    return 0.0


@njit_folded
def _closure(H, VB, L0, w, EA):
    """The four pieces of the closure: (Xcat, Zcat, Xel, Zel), X = Xcat + Xel.

    Xcat and Zcat are the inextensible catenary's span and height, Xel, Zel the
    elastic stretch.  NaN when the cable carries no force and has no weight.
    """
    wl = w * L0
    VA = VB + wl
    TA = hypot(H, VA)
    TB = hypot(H, VB)
    Xel = H * L0 / EA
    Zel = L0 * (VA + VB) / (2.0 * EA)
    if TA + TB <= 0.0:
        return math.nan, math.nan, Xel, Zel
    # (TA - TB)/w = (VA^2 - VB^2)/(w (TA + TB)) = L0 (VA + VB)/(TA + TB)
    Zcat = L0 * (VA + VB) / (TA + TB)
    if H <= 0.0:
        Xcat = 0.0
    elif VA * VB > 0.0:
        # asinh(a) - asinh(b) = asinh(a sqrt(1+b^2) - b sqrt(1+a^2)) and, for a, b of
        # one sign, a sqrt(1+b^2) - b sqrt(1+a^2) = (a^2 - b^2)/(a sqrt(1+b^2) + b sqrt(1+a^2))
        den = VA * TB + VB * TA
        u = wl * (VA + VB) / den
        Xcat = L0 * H * (VA + VB) / den * _asinhc(u)
    elif VA - VB > 0.0:
        # opposite signs (or one end at V = 0): no cancellation, and |VA| + |VB| = w L0
        Xcat = H * L0 * (math.asinh(VA / H) - math.asinh(VB / H)) / (VA - VB)
    else:
        Xcat = L0  # weightless, horizontal
    return Xcat, Zcat, Xel, Zel


@njit
def catenary_ends(H, VB, L0, w, EA):
    """Horizontal span X [m] and height Z [m] of A above B from the end forces.

    ``H`` [N] >= 0 horizontal tension, ``VB`` [N] vertical force on the effector
    (positive up), ``L0`` [m] unstretched length, ``w`` [N/m] >= 0 weight per
    unstretched length, ``EA`` [N] > 0 axial stiffness (``inf``: inextensible).
    Irvine's (1981) closure in a form without 1/w: ``w = 0`` is the straight
    elastic cable, ``H = 0`` the vertical (or folded) one.  Returns (NaN, NaN)
    for a weightless cable without force (H = VB = w = 0): its shape is undefined.
    """
    Xcat, Zcat, Xel, Zel = _closure(H, VB, L0, w, EA)
    return Xcat + Xel, Zcat + Zel


@njit_folded
def _gprime_mean(a, b):
    """Mean of t^2 / (1 + t^2)^(3/2) over [b, a] (12-point Gauss-Legendre)."""
    m = 0.5 * (a + b)
    h = 0.5 * (a - b)
    acc = 0.0
    for k in range(_GL_X.shape[0]):
        t = m + h * _GL_X[k]
        r = 1.0 / hypot(1.0, t)
        tr = t * r
        acc += _GL_W[k] * tr * tr * r
    return 0.5 * acc


@njit
def closure_jac(H, VB, L0, w, EA):
    """(X, Z, dX/dH, dX/dVB, dZ/dH, dZ/dVB) [m, m/N] in one pass (dX/dVB = dZ/dH): the closure
    (:func:`catenary_ends`) and the flexibility (:func:`catenary_jacobian`) together."""
    wl = w * L0
    VA = VB + wl
    TA = hypot(H, VA)
    TB = hypot(H, VB)
    Xcat, Zcat, Xel, Zel = _closure(H, VB, L0, w, EA)
    X = Xcat + Xel
    Z = Zcat + Zel
    flex = L0 / EA
    if TA + TB <= 0.0:
        return X, Z, math.nan, math.nan, math.nan, math.nan
    same = VA * VB > 0.0
    # dX/dVB = dZ/dH = (H/w)(1/TA - 1/TB) = -L0 (VA + VB) H / (TA TB (TA + TB))
    if TA > 0.0 and TB > 0.0:
        hab = H / (TA * TB)
    elif TB > 0.0:
        hab = 1.0 / TB  # H -> 0 with VA = 0
    else:
        hab = 1.0 / TA  # H -> 0 with VB = 0
    J12 = -L0 * (VA + VB) / (TA + TB) * hab
    # dZ/dVB = L0/EA + (VA/TA - VB/TB)/w
    if same:
        den = VA * TB + VB * TA
        fdiff_w = H * H * L0 * (VA + VB) / (TA * TB * den)
    elif VA - VB > 0.0:
        fdiff_w = L0 * (_ratio(VA, TA) - _ratio(VB, TB)) / (VA - VB)
    else:
        fdiff_w = L0 / H  # weightless and horizontal: L0 H^2 / T^3 with T = H
    J22 = flex + fdiff_w
    # dX/dH = L0/EA + (1/w) [G(a) - G(b)], G(t) = asinh t - t/sqrt(1+t^2), G' = t^2/(1+t^2)^1.5
    if H <= 0.0:
        if same:
            den = VA * TB + VB * TA
            u = wl * (VA + VB) / den
            K = L0 * (VA + VB) / den * _asinhc(u)
        else:
            K = math.inf  # X ~ H log(1/H) for a folded vertical cable
    elif wl <= H:
        K = L0 / H * _gprime_mean(VA / H, VB / H)
    else:
        # Xcat/H - (f(VA) - f(VB))/w, a difference of two terms of like size: the
        # quadrature above covers the range where it would cancel badly
        K = Xcat / H - fdiff_w
    J11 = flex + K
    return X, Z, J11, J12, J12, J22


@njit
def catenary_jacobian(H, VB, L0, w, EA):
    """Analytic flexibility d(X, Z)/d(H, VB) [m/N]: (dX/dH, dX/dVB, dZ/dH, dZ/dVB).

    The matrix is symmetric (it is the Hessian of the complementary energy,
    see docs/cable-models.md) and positive definite for H > 0; its inverse is the
    cable's 2x2 stiffness in its plane.  At H = 0 with VB < 0 < VA (folded
    vertical cable) dX/dH is +inf.
    """
    _, _, a, b, c, d = closure_jac(H, VB, L0, w, EA)
    return a, b, c, d


@njit
def catenary_end_tensions(H, VB, L0, w):
    """Tensions [N] at the outlet A and at the attachment B: (T_A, T_B).

    The tension along the cable is sqrt(H^2 + V(s)^2) with V increasing from
    VB to VA, so its largest value is max(T_A, T_B).
    """
    return hypot(H, VB + w * L0), hypot(H, VB)


# ---------------------------------------------------------------------------
# shape
# ---------------------------------------------------------------------------

@njit
def catenary_profile(H, VB, L0, w, EA, s):
    """Points (x(s), z(s)) [m] of the cable at unstretched arc lengths ``s``.

    ``s`` (array, values in [0, L0]) is measured from B; x is horizontal from B
    towards A, z up, both relative to B.  The piece of cable between B and s is
    itself a catenary of length s with the same H and VB, so this is
    :func:`catenary_ends` with L0 replaced by s.
    """
    n = s.shape[0]
    x = np.empty(n)
    z = np.empty(n)
    for i in range(n):
        if s[i] <= 0.0:
            x[i] = 0.0
            z[i] = 0.0
        else:
            x[i], z[i] = catenary_ends(H, VB, s[i], w, EA)
    return x, z


@njit
def catenary_sag(H, VB, L0, w, EA):
    """Largest distance [m] of the cable from its chord line B-A.

    The distance (x Z - z X)/|AB| is largest where the cable's tangent is
    parallel to the chord, i.e. where V(s) = H Z / X; that point always lies on
    the cable (the chord direction is an average of the tangent directions).
    Zero for a weightless (straight) cable and for a vertical one (H = 0: the
    cable lies on the chord line, folded or not).  Returns (sag, s_star), s_star
    [m] the unstretched arc length from B of the farthest point.
    """
    if w <= 0.0 or H <= 0.0:
        return 0.0, 0.0
    X, Z = catenary_ends(H, VB, L0, w, EA)
    c = hypot(X, Z)
    if not (c > 0.0) or not (X > 0.0):
        return 0.0, 0.0
    sstar = (H * (Z / X) - VB) / w
    if sstar < 0.0:
        sstar = 0.0
    elif sstar > L0:
        sstar = L0
    if sstar <= 0.0:
        return 0.0, 0.0
    x, z = catenary_ends(H, VB, sstar, w, EA)
    d = (x * Z - z * X) / c
    return max(d, 0.0), sstar


# ---------------------------------------------------------------------------
# batched forms
# ---------------------------------------------------------------------------

def catenary_ends_batch(H, VB, L0, w, EA):
    """:func:`catenary_ends` over arrays of equal length n (blocks on threads): returns (X, Z)."""
    X, Z = np.empty(H.shape[0]), np.empty(H.shape[0])
    run_blocks(_ends_block, H.shape[0], H, VB, L0, w, EA, X, Z, grain=1024)
    return X, Z


@njit
def _ends_block(k0, k1, H, VB, L0, w, EA, X, Z):
    for i in range(k0, k1):
        X[i], Z[i] = catenary_ends(H[i], VB[i], L0[i], w[i], EA[i])


@njit
def span_height(ax, ay, az, bx, by, bz):
    """The cable's vertical plane from outlet A and attachment B [m] (z up).

    Returns (X, Z, ux, uy): horizontal span, height of A above B, and the
    horizontal unit vector from B towards A ((0, 0) for a vertical cable).  The
    force of the cable on the effector is H (ux, uy, 0) + VB (0, 0, 1).
    """
    dx = ax - bx
    dy = ay - by
    X = hypot(dx, dy)
    if X > 0.0:
        return X, az - bz, dx / X, dy / X
    return 0.0, az - bz, 0.0, 0.0
