"""The sagging cables' fixed point: tensions t = Q(t), Q the minimum-norm tensions of W(t).

For every cable, :func:`~cdpr_design.kernels.sag_shapes.shapes_for` finds the shape whose
effector-end tension is t_i and builds the structure matrix W(t) from the end-force
directions; the map Q takes the minimum-norm tensions of W(t) under the bounds shifted so
that they hold along the whole cable.  :func:`iterate` solves t = Q(t) by fixed-point steps
while they contract, and
:func:`solve` follows damped Newton steps otherwise; :func:`solve` follows the solution from weightless cables
to heavy ones where the straight start is too far from it.  The map
contracts with a factor of about w L / (2 T) (a cable's weight over twice its tension), so a
few iterations suffice for taut cables.

Everything works in a pose's scratch (:data:`FixedScratch` in a :data:`SagScratch`, :func:`make_sag_scratch`,
allocated once per block of poses): nothing here allocates.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import njit, njit_folded
from cdpr_design.kernels.hsm import make_scratch
from cdpr_design.kernels.sag_shapes import (CW_HI, CW_L0, CW_LO, CW_TAU, CW_TH, CW_TM, CW_TP, CW_X, CW_Z, NCW,
                                            SagCables, shapes_for)
from cdpr_design.kernels.scalar import hypot
from cdpr_design.kernels.tension_qp import min_norm_tensions, min_norm_tensions_square, reduction

#: Status of a pose (``status`` column of a sagging sweep).
#: Converged: feasible or not by its margin and tensions.
SAG_OK = 0
#: No tensions >= t_min balance the load (with the cables' shapes): infeasible, margin NaN.
SAG_NO_TENSIONS = 1
#: No catenary: the load needs a heavy cable to pull with less than its least tension
#: (:func:`~cdpr_design.kernels.cable_shape.least_tension`; no tensions balance the load once
#: it is held there), or a cable's shape could not be found: infeasible, margin NaN.
SAG_NO_CATENARY = 2
#: The fixed point did not converge in the iterations allowed: infeasible, margin NaN.
SAG_NOT_CONVERGED = 3
#: A zero-length cable or a rank-deficient structure matrix: infeasible, margin NaN.
SAG_SINGULAR = 4

#: The smallest step of the weight fraction in :func:`continued`.
MIN_WEIGHT_STEP = 1.0 / 256.0
#: Equilibrium tolerance of the fixed point: |W t - w| <= SAG_TOL (1 + |w| + max t) [N].
SAG_TOL = 1e-13

#: The fixed point's scratch: ``W`` (n, m) the structure matrix, ``cw`` (m, NCW) the cables' work
#: columns (:mod:`~cdpr_design.kernels.sag_shapes`), ``lo``/``hi`` (m,) the shifted bounds [N],
#: ``inf_hi`` (m,) all inf, ``qp`` the tension QP's arrays (a
#: :data:`~cdpr_design.kernels.tension_qp.Reduction` for m = n, else the whole
#: :func:`~cdpr_design.kernels.hsm.make_scratch`), ``work`` (6 + m, m): :func:`iterate`'s rows (the
#: map's tensions at t and at a trial t, the straight start, the continuation's weights, the Newton
#: step's right-hand side and trial t, then its m x m Jacobian).  Only what the fixed point reads:
#: its functions are called many times a pose, and a compiled function counts a reference to every
#: array it is handed on every call.
FixedScratch = namedtuple("FixedScratch", "W cw lo hi inf_hi qp work")
#: A sagging pose's scratch: ``fixed`` (:data:`FixedScratch`), ``tq`` (m,) the tensions being
#: solved for [N], ``scr`` the margin's (:func:`~cdpr_design.kernels.hsm.make_scratch`; ``fixed.qp``
#: works in its arrays).
SagScratch = namedtuple("SagScratch", "fixed tq scr")


def make_sag_scratch(n, m, nv):
    """A :data:`SagScratch` for ``n`` wrench rows, ``m`` cables and ``nv`` required wrenches (numpy,
    called from Python: the blocks' loops allocate nothing)."""
    scr = make_scratch(n, m, nv)
    qp = reduction(scr) if m == n else scr
    fixed = FixedScratch(np.empty((n, m)), np.empty((m, NCW)), np.empty(m), np.empty(m), np.full(m, np.inf), qp,
                         np.empty((6 + m, m)))
    return SagScratch(fixed, np.empty(m), scr)


@njit_folded
def _balanced(W, t, w0, tol):
    """Whether W t = w0 to tol (1 + |w0| + max t) [N]."""
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
        if abs(acc - w0[k]) > tol * (1.0 + wn):
            return False
    return True


@njit_folded
def no_tensions(cw, lo):
    """The status of a pose whose bounds admit no tensions: :data:`SAG_NO_CATENARY` when a
    cable's lower bound is its least tension, else :data:`SAG_NO_TENSIONS`."""
    for i in range(lo.shape[0]):
        if lo[i] == cw[i, CW_TM]:
            return SAG_NO_CATENARY
    return SAG_NO_TENSIONS


@njit_folded
def distribute(W, w0, lo, hi, inf_hi, t, qp, redundant):
    """Minimum-norm tensions ``t`` [N] of ``W`` for the wrench ``w0`` under (lo, hi); failing that
    under (lo, ``inf_hi``), in the QP's arrays ``qp`` (a :data:`FixedScratch`'s).  Returns 2, 1 or 0
    (none).  ``redundant``: None where m = n (the square case alone), else m - n."""
    if _min_norm(W, w0, lo, hi, t, qp, redundant):
        return 2
    if _min_norm(W, w0, lo, inf_hi, t, qp, redundant):
        return 1
    return 0


@njit_folded
def _min_norm(W, w, lo, hi, t, qp, redundant):
    """:func:`~cdpr_design.kernels.tension_qp.min_norm_tensions`, its square case alone (in the
    :data:`~cdpr_design.kernels.tension_qp.Reduction` ``qp``) where ``redundant`` is None."""
    if redundant is None:
        return min_norm_tensions_square(W, w, lo, hi, t, qp)
    return min_norm_tensions(W, w, lo, hi, t, qp)


@njit
def _fixed_map(t, q, Rb, w0, cab, sc, redundant):
    """q = the minimum-norm tensions for the shapes of t (``sc``'s W, cw, lo, hi follow t).

    Returns (code, fit): code 2 (within the shifted bounds), 1 (lower bounds
    only), 0 (no tensions balance the load) or -1 (a cable has no shape with
    its tension); fit is :func:`~cdpr_design.kernels.sag_shapes.shapes_for`'s (2: a cable was
    raised to its least tension, so t is not yet consistent with W).
    """
    W, cw, lo, hi = sc.W, sc.cw, sc.lo, sc.hi
    fit = shapes_for(t, Rb, cab, cw, W, 60)
    code = -1
    if fit != 0:
        for i in range(t.shape[0]):
            lo[i] = cw[i, CW_LO]
            hi[i] = cw[i, CW_HI]
        code = distribute(W, w0, lo, hi, sc.inf_hi, q, sc.qp, redundant)
    return code, fit


@njit_folded
def _gap(t, q):
    g = 0.0
    for i in range(t.shape[0]):
        g = max(g, abs(q[i] - t[i]))
    return g


@njit_folded
def _solve_in_place(J, b):
    """Solve J x = b by Gaussian elimination with partial pivoting (x in b); False if singular."""
    m = b.shape[0]
    scale = 0.0
    for i in range(m):
        for j in range(m):
            scale = max(scale, abs(J[i, j]))
    for k in range(m):
        p = k
        for i in range(k + 1, m):
            if abs(J[i, k]) > abs(J[p, k]):
                p = i
        if not (abs(J[p, k]) > 1e-14 * scale):
            return False
        if p != k:
            for j in range(m):
                J[k, j], J[p, j] = J[p, j], J[k, j]
            b[k], b[p] = b[p], b[k]
        for i in range(k + 1, m):
            f = J[i, k] / J[k, k]
            for j in range(k, m):
                J[i, j] -= f * J[k, j]
            b[i] -= f * b[k]
    for k in range(m - 1, -1, -1):
        acc = b[k]
        for j in range(k + 1, m):
            acc -= J[k, j] * b[j]
        b[k] = acc / J[k, k]
    return True


@njit_folded
def _newton_step(t, q, Rb, w0, cab, sc, redundant):
    """One damped Newton step on G(t) = Q(t) - t (finite-difference Jacobian, one column
    per cable); t is updated in place.  Returns the map's (code, fit) at the new t (code -2: no step).
    The map's tensions at a trial t, the Jacobian, the right-hand side and the trial tensions
    are rows of ``sc.work`` (:data:`FixedScratch`)."""
    m = t.shape[0]
    work = sc.work
    qh = work[1]
    r0 = _fixed_map(t, q, Rb, w0, cab, sc, redundant)[0]
    if r0 <= 0:
        return -2, 0
    g0 = _gap(t, q)
    J, rhs, th = work[6:], work[4], work[5]
    for i in range(m):
        th[i] = t[i]
    for j in range(m):
        h = 1e-7 * (1.0 + abs(t[j]))
        th[j] = t[j] + h
        rj = _fixed_map(th, qh, Rb, w0, cab, sc, redundant)[0]
        if rj <= 0:
            h = -h
            th[j] = t[j] + h
            rj = _fixed_map(th, qh, Rb, w0, cab, sc, redundant)[0]
            if rj <= 0:
                return -2, 0
        th[j] = t[j]
        for i in range(m):
            J[i, j] = (1.0 if i == j else 0.0) - (qh[i] - q[i]) / h
    for i in range(m):
        rhs[i] = q[i] - t[i]
    if not _solve_in_place(J, rhs):
        return -2, 0
    d = rhs
    alpha = 1.0
    for _ in range(12):
        for i in range(m):
            th[i] = max(t[i] + alpha * d[i], 0.0)
        r, fit = _fixed_map(th, qh, Rb, w0, cab, sc, redundant)
        if r > 0 and _gap(th, qh) < g0:
            for i in range(m):
                t[i] = th[i]
                q[i] = qh[i]
            return r, fit
        alpha *= 0.5
    return -2, 0


@njit
def iterate(t, Rb, w0, cab, sc, maxit, redundant):
    """Solve t = Q(t) from the straight tensions ``t`` (m,) [N] (in place) for the cables ``cab``
    (:data:`~cdpr_design.kernels.sag_shapes.SagCables`) attached at ``Rb`` (m, 3) [m] and the
    required wrench ``w0`` (n,) [N, N m], in the scratch ``sc`` (:data:`FixedScratch`, its ``cw``
    holding the spans): fixed-point steps while they contract by half or better, damped Newton
    steps otherwise, at most ``maxit`` iterations.  Returns (status, code, iterations); on
    SAG_OK, W, cw, lo, hi hold the shapes of the final t and code is the map's (2 or 1)."""
    m = t.shape[0]
    cw, W, lo = sc.cw, sc.W, sc.lo
    q, qh = sc.work[0], sc.work[1]
    r, fit = _fixed_map(t, q, Rb, w0, cab, sc, redundant)
    bump = 0
    while r == -1 and bump < 8:
        # a cable has no shape at its starting tension: start higher
        for i in range(m):
            t[i] = 1.5 * t[i] + 0.5 * cab.w[i] * hypot(cw[i, CW_X], cw[i, CW_Z])
            cw[i, CW_TH] = math.nan
            cw[i, CW_L0] = math.nan
        r, fit = _fixed_map(t, q, Rb, w0, cab, sc, redundant)
        bump += 1
    # one exit (every return would release the scratch's arrays again)
    status, code, iters = SAG_NOT_CONVERGED, 0, maxit
    if r == -1:
        status, iters = SAG_NO_CATENARY, 0
    elif r == 0:
        status, iters = no_tensions(cw, lo), 0
    else:
        g = _gap(t, q)
        for it in range(1, maxit + 1):
            tscale = 1.0
            for i in range(m):
                tscale = max(tscale, abs(t[i]))
            if fit == 1 and g <= 1e-9 * tscale and _balanced(W, t, w0, SAG_TOL):
                status, code, iters = SAG_OK, r, it
                break
            r2, fit2 = _fixed_map(q, qh, Rb, w0, cab, sc, redundant)
            if r2 > 0:
                g2 = _gap(q, qh)
                if g2 <= 0.5 * g or g2 <= 1e-13 * tscale or fit2 == 2:
                    for i in range(m):
                        t[i] = q[i]
                        q[i] = qh[i]
                    r, fit, g = r2, fit2, g2
                    continue
            r, fit = _newton_step(t, q, Rb, w0, cab, sc, redundant)
            if r == -2:
                # a damped fixed-point step: half way to the map's tensions
                for i in range(m):
                    qh[i] = 0.5 * (t[i] + q[i])
                r, fit = _fixed_map(qh, q, Rb, w0, cab, sc, redundant)
                if r > 0:
                    for i in range(m):
                        t[i] = qh[i]
            if r == 0:
                status, iters = no_tensions(cw, lo), it
                break
            if r < 0:
                # round-off stalls the steps: accept a balance ten times looser, else give up
                r, fit = _fixed_map(t, q, Rb, w0, cab, sc, redundant)
                if r > 0 and fit == 1 and _gap(t, q) <= 1e-9 * tscale and _balanced(W, t, w0, 10.0 * SAG_TOL):
                    status, code = SAG_OK, r
                iters = it
                break
            g = _gap(t, q)
    return status, code, iters


@njit_folded
def solve(t, Rb, w0, cab, sc, maxit, redundant):
    """t = Q(t) from the straight-cable tensions ``t`` (m,) [N] (in place) by :func:`iterate`; where
    that fails, followed from straight cables to heavy ones: the cables' weight per length is
    ``s w`` with s raised from 0 to 1, each step started from the tensions and shapes of the
    last converged s.  The continuation is the fallback when the straight start is too far
    from the solution for the fixed point (a light effector on heavy cables: at the straight
    tensions the cables' end forces point below the horizontal and no tensions balance the
    load, yet a solution exists at higher tensions).  A step that fails is halved, down to
    :data:`MIN_WEIGHT_STEP`; then the pose keeps the status of the first attempt.  Returns
    :func:`iterate`'s (status, code, iterations), ``t`` holding the tensions on SAG_OK;
    ``sc.work[2]`` (the straight start) and ``sc.work[3]`` (the weights) are overwritten.
    One call of :func:`iterate` for both, so that it is compiled into its caller once.
    """
    m = t.shape[0]
    cw, t0, ws = sc.cw, sc.work[2], sc.work[3]
    light = SagCables(cab.rows, cab.up, ws, cab.EA, cab.tmin, cab.tmax)
    for i in range(m):
        t0[i] = t[i]
        ws[i] = cab.w[i]
    first = SAG_OK
    s = 0.0
    ds = 0.25
    s1 = 1.0
    total = 0
    while True:
        status, code, it = iterate(t, Rb, w0, light, sc, maxit, redundant)
        total += it
        if status == SAG_OK:
            if s1 == 1.0:
                return SAG_OK, code, total
            s = s1
            for i in range(m):
                t0[i] = t[i]
            ds = min(2.0 * ds, 1.0 - s)
        elif first == SAG_OK:
            first = status  # the straight start failed: follow the weight from 0
            for i in range(m):
                cw[i, CW_TH] = math.nan
                cw[i, CW_L0] = math.nan
        else:
            ds *= 0.5
            if ds < MIN_WEIGHT_STEP:
                return first, 0, total
        if not s < 1.0:
            return first, 0, total
        s1 = min(1.0, s + ds)
        for i in range(m):
            ws[i] = cab.w[i] if s1 == 1.0 else s1 * cab.w[i]
            t[i] = t0[i]
            # the least tension and the secant start belong to the last weight
            cw[i, CW_TM] = math.nan
            cw[i, CW_TAU] = math.nan
            cw[i, CW_TP] = math.nan
