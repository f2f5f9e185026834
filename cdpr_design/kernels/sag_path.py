"""Sagging cables along a sampled path: :func:`cdpr_design.kernels.sagging.sag_pose` for many samples.

Every sample has its own pose, orientation and required wrench (gravity plus
the effector's inertia), so this is a loop over independent samples rather
than a grid.  A sample whose converged shapes need tensions outside the
bounds is solved again under the lower bound 0 and no upper bound, so that
its tensions and unstretched lengths are still known (the caller flags it
infeasible, as the straight model reports tensions outside the bounds).
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.kernels._jit import njit_noref
from cdpr_design.kernels.parallel import run_blocks
from cdpr_design.kernels.pose import RowBlock
from cdpr_design.kernels.sagging import SAG_NO_TENSIONS, SAG_OK, fixed_point, redundancy, sag_buffers, sag_pose


def sag_samples(P, Rb, A, rows, up, w, EA, wreq, tmin, tmax, combos, maxit,
                tensions, outlet, L0, sag, lengths, status, feasible):
    """Sagging inverse statics of k samples.

    Inputs: ``P`` (k, 3) effector positions [m], ``Rb`` (k, m, 3) rotated
    attachments [m], ``A`` (m, 3) outlets [m], ``rows`` the motion's wrench
    rows, ``up`` (3,), ``w`` (m,) [N/m], ``EA`` (m,) [N], ``wreq`` (k, n)
    required wrench of each sample [N, N m], ``tmin``/``tmax`` (m,) [N],
    ``combos`` as for :func:`sag_pose`, ``maxit`` fixed-point iterations.
    Outputs (k, m): effector-end ``tensions`` [N], ``outlet`` tensions [N],
    unstretched lengths ``L0`` [m], ``sag`` [m], chord ``lengths`` [m]
    (NaN where the sample has no solution); ``status`` (k,) int8 (the
    kernel's SAG_* code); ``feasible`` (k,) uint8: converged with tensions
    within the bounds along the whole cable.
    """
    redundant = redundancy(rows.shape[0], A.shape[0])
    iterate = fixed_point(up, w, EA, tmin, tmax, rows, maxit, redundant)
    run_blocks(_SAMPLES_BLOCK, P.shape[0], P, Rb, A, rows, up, w, EA, wreq, tmin, tmax, combos, maxit,
               tensions, outlet, L0, sag, lengths, status, feasible, redundant, iterate, grain=4)


def _samples_dims(P, Rb, A, rows, *rest):
    """(n, m, nv) of :func:`sag_samples`' arguments: one required wrench a sample."""
    return rows.shape[0], A.shape[0], 1


def _sample_buffers(n, m, nv):
    """:func:`~cdpr_design.kernels.sagging.sag_buffers`, then a sample's lower bounds for its
    second solve (zeros (m,) [N]) and its required wrench (1, n) [N, N m]."""
    return sag_buffers(n, m, nv) + (np.zeros(m), np.empty((1, n)))


@njit_noref
def _samples_loop(k0, k1, P, Rb, A, rows, up, w, EA, wreq, tmin, tmax, combos, maxit,
                  tensions, outlet, L0, sag, lengths, status, feasible, redundant, iterate,
                  W, cw, lo, hi, inf_hi, tq, scr, work, t, ta, l0, sg, L, zero, wj):
    """Samples k0..k1-1 of :func:`sag_samples` (``redundant``:
    :func:`~cdpr_design.kernels.sagging.redundancy`; ``iterate``:
    :func:`~cdpr_design.kernels.sagging.fixed_point`), with the block's buffers (:func:`_sample_buffers`)."""
    m = A.shape[0]
    n = rows.shape[0]
    for j in range(k0, k1):
        for r in range(n):
            wj[0, r] = wreq[j, r]
        Rj = Rb[j]
        st, ok, _, _ = sag_pose(P[j, 0], P[j, 1], P[j, 2], Rj, A, rows, up, w, EA, wj, tmin, tmax,
                                combos, 0, maxit, t, ta, l0, sg, L, W, cw, lo, hi, inf_hi, tq, scr, work,
                                redundant, iterate)
        solved = ok
        if st == SAG_OK and not ok:
            # converged but outside the bounds: the same pose under [0, inf)
            st, solved, _, _ = sag_pose(P[j, 0], P[j, 1], P[j, 2], Rj, A, rows, up, w, EA, wj, zero,
                                        inf_hi, combos, 0, maxit, t, ta, l0, sg, L, W, cw, lo, hi, inf_hi,
                                        tq, scr, work, redundant, iterate)
            if st == SAG_OK and not solved:
                st = SAG_NO_TENSIONS
        status[j] = st
        feasible[j] = 1 if ok else 0
        for i in range(m):
            # sag_pose may leave its scratch in the outputs when it gives up: NaN unless solved
            tensions[j, i] = t[i] if solved else math.nan
            outlet[j, i] = ta[i] if solved else math.nan
            L0[j, i] = l0[i] if solved else math.nan
            sag[j, i] = sg[i] if solved else math.nan
            lengths[j, i] = L[i]


_SAMPLES_BLOCK = RowBlock(_samples_loop, _samples_dims, buffers=_sample_buffers)
