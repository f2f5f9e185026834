"""Sagging cables at given effector-end tensions: their shapes and the structure matrix they make.

The step of the sagging statics' fixed point (:mod:`cdpr_design.kernels.sag_fixed`) that
turns tensions into shapes: each cable's elastic catenary in the vertical plane through its
outlet A and its attachment B (:func:`~cdpr_design.kernels.cable_shape.cable_for_tension`),
and the structure matrix from the end-force directions.  The per-cable state of a pose is a
row of the work array ``cw`` (m, :data:`NCW`), its columns named by the ``CW_*`` indices.

Vertical: ``up`` is the unit vector against gravity; for a planar robot it lies in the plane
of motion, so every cable plane is that plane.
"""

from __future__ import annotations

import math
from collections import namedtuple

from cdpr_design.kernels._jit import njit, njit_folded
from cdpr_design.kernels.cable_shape import cable_for_tension, least_tension
from cdpr_design.kernels.geometry import cable_vector, fill_column
from cdpr_design.kernels.scalar import hypot

#: The cables as the sagging kernels see them: ``rows`` the motion's wrench rows (int64),
#: ``up`` (3,) the unit vector against gravity, ``w`` (m,) weight per length [N/m] (0: a
#: straight elastic cable), ``EA`` (m,) axial stiffness [N], ``tmin``/``tmax`` (m,) the
#: tension bounds [N].  Every array C-contiguous float64 (``rows`` int64).
SagCables = namedtuple("SagCables", "rows up w EA tmin tmax")

#: An effector-end tension at or below SLACK times the largest is a slack cable
#: (a zero lower bound reached) if it is weightless or hangs straight down from its
#: outlet: it exerts no force and its length is undetermined.  A heavy cable is
#: never slack: it holds at least its least tension (:func:`least_tension`).
SLACK = 1e-9

# per-cable work columns (array ``cw`` (m, NCW)): span X, height Z [m], horizontal unit vector,
# end-force angle th [rad], unstretched length L0 [m], end forces H, VB [N], the bounds shifted to
# hold along the whole cable LO, HI [N], the outlet tension TA [N]
CW_X, CW_Z, CW_UX, CW_UY, CW_UZ, CW_TH, CW_L0, CW_H, CW_VB, CW_LO, CW_HI, CW_TA = range(12)
# the cable's least tension and its shape (:func:`least_tension`; NaN until needed)
CW_TM, CW_HM, CW_VM, CW_LM = range(12, 16)
# the fixed point's previous residual g - x and unrelaxed iterate g (for the relaxation)
CW_RP, CW_GP = 16, 17
# the tension of the shape in (th, L0), and the previous shape's (tension, th, L0): a secant start
CW_TAU, CW_TP, CW_THP, CW_LP = range(18, 22)
#: Columns of the per-cable work array ``cw``.
NCW = 22


@njit
def span(px, py, pz, Rb, A, up, cw, lengths):
    """Per-cable chord ``lengths`` (m,) [m], and in ``cw`` the span X, height Z [m] and horizontal
    unit vector of each cable's plane at the effector position (px, py, pz) [m] (``Rb`` (m, 3)
    rotated attachments, ``A`` (m, 3) outlets [m], ``up`` (3,)); the shapes reset to unknown.
    Returns False if a length is 0."""
    ok = True
    for i in range(A.shape[0]):
        lx, ly, lz, li = cable_vector(A, Rb, i, px, py, pz)
        lengths[i] = li
        if li <= 1e-12:
            ok = False
        Z = lx * up[0] + ly * up[1] + lz * up[2]
        hx = lx - Z * up[0]
        hy = ly - Z * up[1]
        hz = lz - Z * up[2]
        X = math.sqrt(hx * hx + hy * hy + hz * hz)
        cw[i, CW_X] = X
        cw[i, CW_Z] = Z
        if X > 1e-14 * li:
            cw[i, CW_UX], cw[i, CW_UY], cw[i, CW_UZ] = hx / X, hy / X, hz / X
        else:
            cw[i, CW_X] = 0.0
            cw[i, CW_UX], cw[i, CW_UY], cw[i, CW_UZ] = 0.0, 0.0, 0.0
        cw[i, CW_TH] = math.nan
        cw[i, CW_L0] = math.nan
        cw[i, CW_TM] = math.nan
        cw[i, CW_TAU] = math.nan
        cw[i, CW_TP] = math.nan
    return ok


@njit_folded
def _least_shape(i, X, Z, w, EA, cw):
    """Cable i's least tension (:func:`least_tension`), computed once per pose into ``cw``."""
    if math.isnan(cw[i, CW_TM]):
        cw[i, CW_TM], cw[i, CW_HM], cw[i, CW_VM], cw[i, CW_LM] = least_tension(X, Z, w, EA)
    return cw[i, CW_TM]


@njit_folded
def _secant_start(i, tau, cw):
    """A start (th, L0) for cable i at tension tau: the last shape, moved along the secant
    through the last two shapes when they are at distinct tensions and tau is not far off."""
    th, L0 = cw[i, CW_TH], cw[i, CW_L0]
    d = cw[i, CW_TAU] - cw[i, CW_TP]
    if d != 0.0 and math.isfinite(d) and math.isfinite(cw[i, CW_THP]) and math.isfinite(cw[i, CW_LP]):
        s = (tau - cw[i, CW_TAU]) / d
        if abs(s) <= 4.0:
            th1 = th + s * (th - cw[i, CW_THP])
            L1 = L0 + s * (L0 - cw[i, CW_LP])
            if abs(th1) < 1.5 and L1 > 0.0:
                return th1, L1
    return th, L0


@njit_folded
def _slack_column(i, X, Z, rows, up, tmin, tmax, Rb, cw, W):
    """A slack cable: no force, shape and length undetermined; column along the chord."""
    cw[i, CW_TH] = math.nan
    cw[i, CW_L0] = math.nan
    cw[i, CW_TAU] = math.nan
    cw[i, CW_H] = 0.0
    cw[i, CW_VB] = 0.0
    cw[i, CW_TA] = math.nan
    cw[i, CW_LO] = tmin[i]
    cw[i, CW_HI] = tmax[i]
    c = hypot(X, Z)
    if X > 0.0:
        dx = (X * cw[i, CW_UX] + Z * up[0]) / c
        dy = (X * cw[i, CW_UY] + Z * up[1]) / c
        dz = (X * cw[i, CW_UZ] + Z * up[2]) / c
    else:
        s = 1.0 if Z > 0.0 else -1.0
        dx, dy, dz = s * up[0], s * up[1], s * up[2]
    fill_column(W, i, rows, dx, dy, dz, Rb[i, 0], Rb[i, 1], Rb[i, 2])


@njit_folded
def _shape_column(i, tau, H, VB, L0, rows, up, w, tmin, tmax, Rb, cw, W):
    """Cable i's shape (H, VB [N], L0 [m]) at effector-end tension tau [N] into ``cw`` (the
    bounds shifted to hold along the whole cable, the outlet tension), and its column of ``W``
    along the end force."""
    X = cw[i, CW_X]
    th = math.atan2(VB, H)
    cw[i, CW_TH] = th
    cw[i, CW_L0] = L0
    cw[i, CW_H] = H
    cw[i, CW_VB] = VB
    VA = VB + w[i] * L0
    TA = hypot(H, VA)
    tmax_along = max(TA, tau)
    tmin_along = H if (VB < 0.0 < VA) else min(TA, tau)
    cw[i, CW_TA] = TA
    cw[i, CW_LO] = tmin[i] + (tau - tmin_along)
    if not math.isnan(cw[i, CW_TM]):
        cw[i, CW_LO] = max(cw[i, CW_LO], cw[i, CW_TM])
    cw[i, CW_HI] = tmax[i] - (tmax_along - tau)
    if X > 0.0:
        ch = H / tau
        sv = VB / tau
        dx = ch * cw[i, CW_UX] + sv * up[0]
        dy = ch * cw[i, CW_UY] + sv * up[1]
        dz = ch * cw[i, CW_UZ] + sv * up[2]
    else:
        s = 1.0 if VB > 0.0 else -1.0
        dx, dy, dz = s * up[0], s * up[1], s * up[2]
    fill_column(W, i, rows, dx, dy, dz, Rb[i, 0], Rb[i, 1], Rb[i, 2])


@njit_folded
def shapes_for(t, Rb, cab, cw, W, maxit):
    """Cable shapes for effector-end tensions ``t`` (m) [N] of the cables ``cab``
    (:data:`SagCables`) attached at ``Rb`` (m, 3) [m]: the structure matrix ``W`` (n, m)
    from the end-force directions, and in ``cw`` each cable's (th, L0, H, VB), the
    bounds shifted to hold along the whole cable (lo, hi) and the outlet tension.
    ``cw`` must hold the spans from :func:`span` (and the previous th, L0 as a start);
    ``maxit`` bounds each cable's Newton iterations.

    A heavy cable cannot pull with less than its least tension (:func:`least_tension`):
    asked for less, it takes that least-tension shape, and from then on its lower bound
    is at least that tension.  Only a weightless cable, or one hanging straight down
    from its outlet, is slack at (near) zero tension.
    Returns 1; 2 when a cable was raised to its least tension (``t`` is then not
    consistent with ``W``); 0 when a cable has no shape.
    """
    # the bundle's arrays bound once: each read of a field in the loop would count a reference
    rows, up, w, EA, tmin, tmax = cab.rows, cab.up, cab.w, cab.EA, cab.tmin, cab.tmax
    tscale = 1.0
    for i in range(t.shape[0]):
        tscale = max(tscale, abs(t[i]))
    out = 1
    for i in range(t.shape[0]):
        X = cw[i, CW_X]
        Z = cw[i, CW_Z]
        can_slack = w[i] == 0.0 or (X <= 0.0 and Z > 0.0)
        if t[i] <= SLACK * tscale and can_slack:
            _slack_column(i, X, Z, rows, up, tmin, tmax, Rb, cw, W)
            continue
        tau = t[i]
        ok = False
        if tau > 0.0:
            th0, L00 = _secant_start(i, tau, cw)
            H, VB, L0, ok = cable_for_tension(X, Z, tau, w[i], EA[i], th0, L00, maxit)
            if not ok and not math.isnan(th0):
                # the previous shapes can be a poor start after a long step: start afresh
                H, VB, L0, ok = cable_for_tension(X, Z, tau, w[i], EA[i], math.nan, math.nan, maxit)
        cw[i, CW_TP], cw[i, CW_THP], cw[i, CW_LP] = cw[i, CW_TAU], cw[i, CW_TH], cw[i, CW_L0]
        cw[i, CW_TAU] = tau if ok else math.nan
        if not ok:
            tm = _least_shape(i, X, Z, w[i], EA[i], cw)
            if not (tau <= tm * (1.0 + 1e-12)):
                out = 0  # above the least tension (or NaN), and yet no shape
                break
            if tau < tm * (1.0 - 1e-12):
                out = 2
            tau, H, VB, L0 = tm, cw[i, CW_HM], cw[i, CW_VM], cw[i, CW_LM]
        _shape_column(i, tau, H, VB, L0, rows, up, w, tmin, tmax, Rb, cw, W)
    return out


@njit
def straight_columns(Rb, A, px, py, pz, rows, W):
    """The structure matrix ``W`` (n, m) of straight cables at (px, py, pz) [m] (``Rb`` (m, 3)
    rotated attachments, ``A`` (m, 3) outlets [m]); every chord must have a length."""
    for i in range(A.shape[0]):
        lx, ly, lz, li = cable_vector(A, Rb, i, px, py, pz)
        fill_column(W, i, rows, lx / li, ly / li, lz / li, Rb[i, 0], Rb[i, 1], Rb[i, 2])
