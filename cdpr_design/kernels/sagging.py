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
   (1e-12 where round-off stalls the Newton steps)
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

Compile time.  The fixed point is a chain of calls (a block's loop ->
:func:`sag_pose` -> :func:`_continued` -> :func:`_iterate` -> :func:`_newton_step`
-> :func:`_fixed_map` -> the shapes and the tensions), and numba optimises a
compiled function together with everything it calls, in the module of each
caller again: every level cost the whole depth below it once more.  The
functions with one call site in the chain (:func:`sag_pose` in each block,
:func:`_continued`, :func:`_newton_step`) are folded into their callers
(:data:`~cdpr_design.kernels._jit.njit_folded`), the outputs identical.
:func:`_iterate`, called twice, is not: folded as well (twice, or once with the
straight start made the first pass of :func:`_continued`'s loop) it compiled
longer: LLVM's time on one function grows faster than its size, so a large
body is worth folding only where it saves a level.
:func:`_distribute` and :func:`_min_norm` (two call sites, a few calls each) are
folded too: each was a level over the whole tension QP, the outputs
identical.  Measured and left: folding the QP's own thin levels below them as well
(:func:`~cdpr_design.kernels.tension_qp.min_norm_tensions_square`, ``_reduced``,
``null_space_setup``: three pairs, no gain), and :func:`make_sag_scratch` compiled
into its callers (within the noise).  The blocks call :func:`_iterate` through a C
function pointer (:func:`fixed_point`), not linked into their own modules, and the
verdict on the converged pose is :func:`_evaluate`, a function of its own;
:func:`_fixed_map` through a pointer as well gained nothing and slowed the sweep.
The fixed point and everything below it that takes arrays is compiled without numba's
reference counting (:data:`~cdpr_design.kernels._jit.njit_noref`; the Newton step's
Jacobian is in the scratch, :func:`make_sag_scratch`): no counter code around each of the
many calls with a dozen arrays, outputs identical.  So are the blocks' loops over poses, given their
buffers by a Python block (:func:`sag_buffers`, :class:`~cdpr_design.kernels.pose.RowBlock`).
The compile times and sweep times of each of these steps: docs/performance.md.
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.kernels._jit import jitable, njit_folded, njit_noref, pointer_for
from cdpr_design.kernels.parallel import run_blocks
from cdpr_design.kernels.cable_shape import cable_for_tension, least_tension
from cdpr_design.kernels.catenary import catenary_sag
from cdpr_design.kernels.geometry import fill_column, grid_index
from cdpr_design.kernels.hsm import make_scratch
from cdpr_design.kernels.pose import RowBlock, eval_general, eval_square_into
from cdpr_design.kernels.tension_qp import min_norm_tensions, min_norm_tensions_square

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
#: The smallest step of the weight fraction in :func:`_continued`.
MIN_WEIGHT_STEP = 1.0 / 256.0
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


@njit_noref
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


@njit_noref
def _least_shape(i, X, Z, w, EA, cw):
    """Cable i's least tension (:func:`least_tension`), computed once per pose into ``cw``."""
    if math.isnan(cw[i, _TM]):
        cw[i, _TM], cw[i, _HM], cw[i, _VM], cw[i, _LM] = least_tension(X, Z, w, EA)
    return cw[i, _TM]


@njit_noref
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


@njit_noref
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


@njit_noref
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
            if not ok and not math.isnan(th0):
                # the previous shapes can be a poor start after a long step: start afresh
                H, VB, L0, ok = cable_for_tension(X, Z, tau, w[i], EA[i], math.nan, math.nan, maxit)
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


@njit_noref
def _straight_columns(Rb, A, px, py, pz, rows, W):
    for i in range(A.shape[0]):
        lx = A[i, 0] - px - Rb[i, 0]
        ly = A[i, 1] - py - Rb[i, 1]
        lz = A[i, 2] - pz - Rb[i, 2]
        li = math.sqrt(lx * lx + ly * ly + lz * lz)
        fill_column(W, i, rows, lx / li, ly / li, lz / li, Rb[i, 0], Rb[i, 1], Rb[i, 2])


@njit_noref
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


@njit_noref
def _no_tensions(cw, lo):
    """The status of a pose whose bounds admit no tensions: :data:`SAG_NO_CATENARY` when a
    cable's lower bound is its least tension, else :data:`SAG_NO_TENSIONS`."""
    for i in range(lo.shape[0]):
        if lo[i] == cw[i, _TM]:
            return SAG_NO_CATENARY
    return SAG_NO_TENSIONS


@njit_folded
def _distribute(W, w0, lo, hi, inf_hi, t, scr, redundant):
    """Minimum-norm tensions under (lo, hi); failing that under (lo, inf). Returns 2, 1 or 0."""
    if _min_norm(W, w0, lo, hi, t, scr, redundant):
        return 2
    if _min_norm(W, w0, lo, inf_hi, t, scr, redundant):
        return 1
    return 0


@njit_folded
def _min_norm(W, w, lo, hi, t, scr, redundant):
    """:func:`~cdpr_design.kernels.tension_qp.min_norm_tensions`, its square case alone where
    ``redundant`` is None (:func:`redundancy`)."""
    if redundant is None:
        return min_norm_tensions_square(W, w, lo, hi, t, scr)
    return min_norm_tensions(W, w, lo, hi, t, scr)


def redundancy(n: int, m: int):
    """The ``redundant`` argument of the sagging kernels for ``n`` wrench rows and ``m`` cables:
    None for m = n, else m - n.  numba compiles a kernel once per argument type and prunes the
    branches on ``redundant is None`` before typing them, so a square robot's first run compiles
    none of the redundant methods (the QP's and the margin's) and a redundant one none of the
    square ones."""
    return None if m == n else m - n


def fixed_point(up, w, EA, tmin, tmax, rows, maxit, redundant):
    """The fixed point a sagging kernel's blocks give :func:`sag_pose` (its ``iterate``):
    :func:`_iterate` compiled for the types of the kernel's arguments (C-contiguous arrays, as
    :func:`sweep_grid_sagging` takes them) and of its scratch (:func:`make_sag_scratch`), as a
    C function pointer (:func:`~cdpr_design.kernels._jit.pointer_for`).

    The blocks call it through the pointer rather than linking it: numba optimises a compiled
    function together with everything it calls, so a block that called :func:`_iterate` directly
    had the whole fixed point below it (the shapes, the catenaries, the tension QP) optimised by
    LLVM once more in its own module.  The outputs are identical; an indirect call per pose
    costs nothing beside its catenary solves (docs/performance.md)."""
    n, m = rows.shape[0], w.shape[0]
    W, cw, lo, hi, inf_hi, tq, scr, work = make_sag_scratch(n, m, 1)
    Rb, w0 = np.empty((m, 3)), np.empty(n)  # a pose's rotated attachments [m], required wrench [N, N m]
    return pointer_for(_iterate, (tq, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, work,
                                  maxit, redundant))


@njit_folded
def sag_pose(px, py, pz, Rb, A, rows, up, w, EA, wreq, tmin, tmax, combos, kind, maxit,
             t, outlet, L0, sag, lengths, W, cw, lo, hi, inf_hi, tq, scr, work, redundant, iterate):
    """One pose with sagging cables: (status, feasible, margin, iterations).

    Inputs as :func:`cdpr_design.kernels.sweep.sweep_grid` plus ``up`` (3,)
    (unit vector against gravity), ``w`` (m,) [N/m] cable weight per length
    (0: a straight elastic cable) and ``EA`` (m,) [N].  Outputs: ``t``
    effector-end tensions [N], ``outlet`` outlet tensions [N], ``L0``
    unstretched lengths [m], ``sag`` largest distance from the chord [m] (all
    NaN unless the pose is feasible), ``lengths`` chord lengths [m].  ``W``,
    ``cw``, ``lo``, ``hi``, ``inf_hi`` (all inf), ``tq``, ``scr``, ``work`` are
    scratch (:func:`make_sag_scratch`).  ``redundant``: None where m = n, else m - n
    (:func:`redundancy`).  ``iterate``: the fixed point (:func:`fixed_point`).
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
        W[:, :] = math.nan  # no direction to pull in, and no shapes
        return SAG_SINGULAR, False, math.nan, 0
    _straight_columns(Rb, A, px, py, pz, rows, W)
    if _distribute(W, wreq[0], tmin, tmax, inf_hi, tq, scr, redundant) == 0:
        W[:, :] = math.nan
        return SAG_NO_TENSIONS, False, math.nan, 0
    t0 = work[2]
    for i in range(m):
        t0[i] = tq[i]
    status, bounded, it = iterate(tq, Rb, up, w, EA, wreq[0], tmin, tmax, rows, cw, W, lo, hi, inf_hi,
                                  scr, work, maxit, redundant)
    if status != SAG_OK:
        # the straight start can be too far (a light effector on heavy cables): follow the
        # solution from weightless cables; if that fails too, the pose keeps its first status
        st2, b2, it2 = _continued(tq, t0, Rb, up, w, EA, wreq[0], tmin, tmax, rows, cw, W, lo, hi,
                                  inf_hi, scr, work, maxit, redundant, iterate)
        it += it2
        if st2 == SAG_OK:
            status, bounded = st2, b2
    if status != SAG_OK:
        W[:, :] = math.nan  # the shapes are not known
        return status, False, math.nan, it
    for i in range(m):
        lo[i] = cw[i, _LO]
        hi[i] = cw[i, _HI]
    feasible, margin = _evaluate(W, wreq, lo, hi, combos, kind, t, scr, redundant)
    feasible = feasible and bounded == 2
    for i in range(m):
        t[i] = tq[i] if feasible else math.nan
        if feasible and not math.isnan(cw[i, _L0]):
            outlet[i] = cw[i, _TA]
            L0[i] = cw[i, _L0]
            sag[i] = catenary_sag(cw[i, _H], cw[i, _VB], cw[i, _L0], w[i], EA[i])[0]
    return SAG_OK, feasible, margin + 0.0, it


@njit_noref
def _evaluate(W, wreq, lo, hi, combos, kind, t, scr, redundant):
    """(feasible, margin) of the converged structure matrix ``W`` under the shifted bounds: the
    square case alone where ``redundant`` is None.  A function of its own, not in
    :func:`sag_pose`'s body: numba prunes the branch of an argument that is None before it
    inlines the other's :func:`~cdpr_design.kernels.pose.eval_general`, so a square robot's
    kernels do not copy that body in (it would, folded into the blocks).  Both work in the
    scratch ``scr`` (:func:`~cdpr_design.kernels.hsm.make_scratch`; the square case as the
    straight sweeps', :func:`~cdpr_design.kernels.pose.eval_row`): nothing is allocated."""
    if redundant is None:  # the square case's work arrays from the scratch, as the straight sweeps'
        return eval_square_into(W, wreq, lo, hi, kind, t, scr[4], scr[3], scr[0])
    return eval_general(W, wreq, lo, hi, combos, kind, t, scr, redundant)


@njit_noref
def _fixed_map(t, q, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, redundant):
    """q = the minimum-norm tensions for the shapes of t (W, cw, lo, hi follow t).

    Returns (code, fit): code 2 (within the shifted bounds), 1 (lower bounds
    only), 0 (no tensions balance the load) or -1 (a cable has no shape with
    its tension); fit is :func:`shapes_for`'s (2: a cable was raised to its
    least tension, so t is not yet consistent with W).
    """
    fit = shapes_for(t, Rb, up, w, EA, tmin, tmax, rows, cw, W, 60)
    if fit == 0:
        return -1, fit
    for i in range(t.shape[0]):
        lo[i] = cw[i, _LO]
        hi[i] = cw[i, _HI]
    return _distribute(W, w0, lo, hi, inf_hi, q, scr, redundant), fit


@njit_noref
def _gap(t, q):
    g = 0.0
    for i in range(t.shape[0]):
        g = max(g, abs(q[i] - t[i]))
    return g


@njit_noref
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
def _newton_step(t, q, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, qh, work, redundant):
    """One damped Newton step on G(t) = Q(t) - t (finite-difference Jacobian, one column
    per cable); t is updated in place.  Returns the map's (code, fit) at the new t (code -2: no step).
    The Jacobian, the right-hand side and the trial tensions are rows of ``work``
    (:func:`make_sag_scratch`)."""
    m = t.shape[0]
    r0 = _fixed_map(t, q, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, redundant)[0]
    if r0 <= 0:
        return -2, 0
    g0 = _gap(t, q)
    J, rhs, th = work[6:], work[4], work[5]
    for i in range(m):
        th[i] = t[i]
    for j in range(m):
        h = 1e-7 * (1.0 + abs(t[j]))
        th[j] = t[j] + h
        rj = _fixed_map(th, qh, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, redundant)[0]
        if rj <= 0:
            h = -h
            th[j] = t[j] + h
            rj = _fixed_map(th, qh, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, redundant)[0]
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
        r, fit = _fixed_map(th, qh, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, redundant)
        if r > 0 and _gap(th, qh) < g0:
            for i in range(m):
                t[i] = th[i]
                q[i] = qh[i]
            return r, fit
        alpha *= 0.5
    return -2, 0


@njit_noref
def _iterate(t, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, work, maxit, redundant):
    """Solve t = Q(t) from the straight tensions ``t`` (in place): fixed-point steps while they
    contract by half or better, damped Newton steps otherwise.  Returns (status, code, iterations);
    on SAG_OK, W, cw, lo, hi hold the shapes of the final t and code is the map's (2 or 1)."""
    m = t.shape[0]
    q, qh = work[0], work[1]
    r, fit = _fixed_map(t, q, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, redundant)
    bump = 0
    while r == -1 and bump < 8:
        # a cable has no shape at its starting tension: start higher
        for i in range(m):
            t[i] = 1.5 * t[i] + 0.5 * w[i] * math.hypot(cw[i, _X], cw[i, _Z])
            cw[i, _TH] = math.nan
            cw[i, _L0] = math.nan
        r, fit = _fixed_map(t, q, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, redundant)
        bump += 1
    if r == -1:
        return SAG_NO_CATENARY, 0, 0
    if r == 0:
        return _no_tensions(cw, lo), 0, 0
    g = _gap(t, q)
    for it in range(1, maxit + 1):
        tscale = 1.0
        for i in range(m):
            tscale = max(tscale, abs(t[i]))
        if fit == 1 and g <= 1e-9 * tscale and _balanced(W, t, w0, SAG_TOL):
            return SAG_OK, r, it
        r2, fit2 = _fixed_map(q, qh, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, redundant)
        if r2 > 0:
            g2 = _gap(q, qh)
            if g2 <= 0.5 * g or g2 <= 1e-13 * tscale or fit2 == 2:
                for i in range(m):
                    t[i] = q[i]
                    q[i] = qh[i]
                r, fit, g = r2, fit2, g2
                continue
        r, fit = _newton_step(t, q, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, qh, work,
                              redundant)
        if r == -2:
            # a damped fixed-point step: half way to the map's tensions
            for i in range(m):
                qh[i] = 0.5 * (t[i] + q[i])
            r, fit = _fixed_map(qh, q, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, redundant)
            if r > 0:
                for i in range(m):
                    t[i] = qh[i]
        if r == 0:
            return _no_tensions(cw, lo), 0, it
        if r < 0:
            # round-off stalls the steps: accept a balance ten times looser, else give up
            r, fit = _fixed_map(t, q, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, redundant)
            if r > 0 and fit == 1 and _gap(t, q) <= 1e-9 * tscale and _balanced(W, t, w0, 10.0 * SAG_TOL):
                return SAG_OK, r, it
            return SAG_NOT_CONVERGED, 0, it
        g = _gap(t, q)
    return SAG_NOT_CONVERGED, 0, maxit


@njit_folded
def _continued(t, t0, Rb, up, w, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi, scr, work, maxit, redundant,
               iterate):
    """:func:`_iterate` followed from straight cables to heavy ones: the cables' weight per
    length is ``s w`` with s raised from 0 to 1, each step started from the tensions and
    shapes of the last converged s.  The fallback when the straight-cable start ``t0`` [N]
    (m,) is too far from the solution for the fixed point (a light effector on heavy
    cables: at the straight tensions the cables' end forces point below the horizontal and
    no tensions balance the load, yet a solution exists at higher tensions).  A step that
    fails is halved, down to :data:`MIN_WEIGHT_STEP`; then it returns the status of its
    last failure (``iterate``: :func:`_iterate`, as :func:`sag_pose` was given it).  Returns
    :func:`_iterate`'s (status, code, iterations), ``t``
    (m,) holding the tensions on SAG_OK; ``t0`` and ``work[3]`` are overwritten.
    """
    m = t.shape[0]
    ws = work[3]
    s = 0.0
    ds = 0.25
    total = 0
    last = SAG_NOT_CONVERGED
    for i in range(m):
        cw[i, _TH] = math.nan
        cw[i, _L0] = math.nan
    while s < 1.0:
        s1 = min(1.0, s + ds)
        for i in range(m):
            ws[i] = w[i] if s1 == 1.0 else s1 * w[i]
            t[i] = t0[i]
            # the least tension and the secant start belong to the last weight
            cw[i, _TM] = math.nan
            cw[i, _TAU] = math.nan
            cw[i, _TP] = math.nan
        status, code, it = iterate(t, Rb, up, ws, EA, w0, tmin, tmax, rows, cw, W, lo, hi, inf_hi,
                                    scr, work, maxit, redundant)
        total += it
        if status == SAG_OK:
            if s1 == 1.0:
                return SAG_OK, code, total
            s = s1
            for i in range(m):
                t0[i] = t[i]
            ds = min(2.0 * ds, 1.0 - s)
        else:
            last = status
            ds *= 0.5
            if ds < MIN_WEIGHT_STEP:
                return last, 0, total
    return last, 0, total


@jitable
def make_sag_scratch(n, m, nv):
    """Scratch for :func:`sag_pose`: (W, cw, lo, hi, inf_hi, tq, scr, work); ``work`` (6 + m, m)
    holds :func:`_iterate`'s rows (the map's tensions at t and at a trial t, the straight start, the
    continuation's weights, the Newton step's right-hand side and trial t, then its m x m Jacobian)."""
    inf_hi = np.full(m, np.inf)
    return (np.empty((n, m)), np.empty((m, NCW)), np.empty(m), np.empty(m), inf_hi, np.empty(m),
            make_scratch(n, m, nv), np.empty((6 + m, m)))


@jitable
def make_pose_outputs(m):
    """The per-cable outputs of :func:`sag_pose`: (tensions, outlet, L0, sag, lengths), each (m,)."""
    return np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m)


def sweep_grid_sagging(start, count, lower, step, shape, Rb, A, rows, up, w, EA, wreq, tmin, tmax,
                       combos, kind, maxit, feasible, margin, tensions, lengths, outlet, L0, sag, status):
    """:func:`cdpr_design.kernels.sweep.sweep_grid` with sagging cables (:func:`sag_pose`).

    Extra outputs (count, m): ``outlet`` tensions [N], unstretched lengths
    ``L0`` [m], ``sag`` [m]; ``status`` (count,) int8.  Every pose starts from
    its own straight-cable solution, so rows do not depend on the chunking.
    """
    redundant = redundancy(rows.shape[0], A.shape[0])
    iterate = fixed_point(up, w, EA, tmin, tmax, rows, maxit, redundant)
    run_blocks(_GRID_BLOCK, count, start, lower, step, shape, Rb, A, rows, up, w, EA, wreq, tmin, tmax,
               combos, kind, maxit, feasible, margin, tensions, lengths, outlet, L0, sag, status, redundant, iterate,
               grain=16)


def sag_buffers(n, m, nv):
    """A sagging block's buffers: :func:`make_sag_scratch`'s, then :func:`make_pose_outputs`'
    (numpy: the blocks' loops allocate nothing, :class:`~cdpr_design.kernels.pose.RowBlock`)."""
    return make_sag_scratch(n, m, nv) + make_pose_outputs(m)


def _grid_dims(start, lower, step, shape, Rb, A, rows, up, w, EA, wreq, *rest):
    """(n, m, nv) of :func:`sweep_grid_sagging`'s arguments."""
    return rows.shape[0], A.shape[0], wreq.shape[0]


@njit_noref
def _grid_loop(k0, k1, start, lower, step, shape, Rb, A, rows, up, w, EA, wreq, tmin, tmax,
               combos, kind, maxit, feasible, margin, tensions, lengths, outlet, L0, sag, status, redundant,
               iterate, Wb, cw, lo, hi, inf_hi, tq, scr, work, t, ta, l0, sg, L):
    """Rows k0..k1-1 of :func:`sweep_grid_sagging` (``redundant``: :func:`redundancy`; ``iterate``:
    :func:`fixed_point`), with the block's buffers (:func:`sag_buffers`): compiled without
    reference counting, as the straight sweeps' loops (:data:`~cdpr_design.kernels._jit.NOREF`)."""
    m = A.shape[0]
    ny = shape[1]
    nz = shape[2]
    for k in range(k0, k1):
        ix, iy, iz = grid_index(start + k, ny, nz)
        st, f, mg, _ = sag_pose(lower[0] + ix * step[0], lower[1] + iy * step[1], lower[2] + iz * step[2],
                                Rb, A, rows, up, w, EA, wreq, tmin, tmax, combos, kind, maxit,
                                t, ta, l0, sg, L, Wb, cw, lo, hi, inf_hi, tq, scr, work, redundant, iterate)
        status[k] = st
        feasible[k] = 1 if f else 0
        margin[k] = mg
        for i in range(m):
            tensions[k, i] = t[i]
            lengths[k, i] = L[i]
            outlet[k, i] = ta[i]
            L0[k, i] = l0[i]
            sag[k, i] = sg[i]


_GRID_BLOCK = RowBlock(_grid_loop, _grid_dims, buffers=sag_buffers)


def sag_points(P, Rb, A, rows, up, w, EA, wreq, tmin, tmax, combos, kind, maxit,
               feasible, Ws, tensions, outlet, status):
    """:func:`sag_pose` at positions ``P`` (k, 3) [m] (one orientation, in ``Rb``).

    Outputs: ``feasible`` (k,) uint8, ``Ws`` (k, n, m) the converged structure
    matrices (from the end-force directions), ``tensions`` and ``outlet``
    (k, m) [N], ``status`` (k,) int8.  For the sizing, which needs the
    structure matrix of each task pose.
    """
    redundant = redundancy(rows.shape[0], A.shape[0])
    iterate = fixed_point(up, w, EA, tmin, tmax, rows, maxit, redundant)
    run_blocks(_POINTS_BLOCK, P.shape[0], P, Rb, A, rows, up, w, EA, wreq, tmin, tmax, combos, kind, maxit,
               feasible, Ws, tensions, outlet, status, redundant, iterate, grain=16)


def _points_dims(P, Rb, A, rows, up, w, EA, wreq, *rest):
    """(n, m, nv) of :func:`sag_points`' arguments."""
    return rows.shape[0], A.shape[0], wreq.shape[0]


@njit_noref
def _points_loop(k0, k1, P, Rb, A, rows, up, w, EA, wreq, tmin, tmax, combos, kind, maxit,
                 feasible, Ws, tensions, outlet, status, redundant, iterate, Wb, cw, lo, hi, inf_hi, tq, scr, work,
                 t, ta, l0, sg, L):
    """Rows k0..k1-1 of :func:`sag_points` (``redundant``: :func:`redundancy`; ``iterate``:
    :func:`fixed_point`), with the block's buffers (:func:`sag_buffers`)."""
    n = rows.shape[0]
    m = A.shape[0]
    for j in range(k0, k1):
        st, f, mg, _ = sag_pose(P[j, 0], P[j, 1], P[j, 2], Rb, A, rows, up, w, EA, wreq, tmin, tmax,
                                combos, kind, maxit, t, ta, l0, sg, L, Wb, cw, lo, hi, inf_hi, tq, scr, work,
                                redundant, iterate)
        status[j] = st
        feasible[j] = 1 if f else 0
        for r in range(n):
            for i in range(m):
                Ws[j, r, i] = Wb[r, i]
        for i in range(m):
            tensions[j, i] = t[i]
            outlet[j, i] = ta[i]


_POINTS_BLOCK = RowBlock(_points_loop, _points_dims, buffers=sag_buffers)
