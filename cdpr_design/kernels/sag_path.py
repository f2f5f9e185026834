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
from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import njit
from cdpr_design.kernels.parallel import run_blocks
from cdpr_design.kernels.pose import RowBlock
from cdpr_design.kernels.sag_shapes import SagCables
from cdpr_design.kernels.sagging import SAG_NO_TENSIONS, SAG_OK, SagRobot, redundancy, sag_buffers, sag_pose

#: Rows of :func:`sag_samples`, (k, m): effector-end ``tensions`` [N], ``outlet`` tensions [N],
#: unstretched lengths ``L0`` [m], ``sag`` [m], chord ``lengths`` [m] (NaN where the sample has no
#: solution); ``status`` (k,) int8 (the kernel's SAG_* code); ``feasible`` (k,) uint8: converged
#: with tensions within the bounds along the whole cable.
SampleOutputs = namedtuple("SampleOutputs", "tensions outlet L0 sag lengths status feasible")


def sag_samples(P, Rb, robot, out):
    """Sagging inverse statics of k samples, into ``out`` (:data:`SampleOutputs`).

    Inputs: ``P`` (k, 3) effector positions [m], ``Rb`` (k, m, 3) rotated
    attachments [m], ``robot`` a :data:`~cdpr_design.kernels.sagging.SagRobot` whose ``wreq``
    (k, n) holds each sample's required wrench [N, N m] (its ``kind`` static).
    """
    redundant = redundancy(robot.cables.rows.shape[0], robot.A.shape[0])
    run_blocks(_SAMPLES_BLOCK, P.shape[0], P, Rb, robot, out, redundant, grain=4)


def _sample_buffers(n, m, nv):
    """:func:`~cdpr_design.kernels.sagging.sag_buffers` for one required wrench, then a sample's
    lower bounds for its second solve (zeros (m,) [N]) and its required wrench (1, n) [N, N m]."""
    return sag_buffers(n, m, 1) + (np.zeros(m), np.empty((1, n)))


@njit
def _samples_loop(k0, k1, P, Rb, robot, out, redundant, po, sc, zero, wj):
    """Samples k0..k1-1 of :func:`sag_samples` (``redundant``:
    :func:`~cdpr_design.kernels.sagging.redundancy`), with the block's buffers (:func:`_sample_buffers`)."""
    m = robot.A.shape[0]
    n = wj.shape[1]
    cab = robot.cables
    # a sample's robot (its required wrench in wj), and the same under [0, inf)
    one = SagRobot(robot.A, cab, wj, robot.combos, robot.kind, robot.maxit)
    free = SagRobot(robot.A, SagCables(cab.rows, cab.up, cab.w, cab.EA, zero, sc.fixed.inf_hi), wj, robot.combos,
                    robot.kind, robot.maxit)
    for j in range(k0, k1):
        for r in range(n):
            wj[0, r] = robot.wreq[j, r]
        # the sample under its bounds; converged but outside them, the same pose under [0, inf)
        # (one call of sag_pose, so that its fixed point is compiled into this loop once)
        bounds = one
        ok = solved = False
        st = SAG_OK
        for attempt in range(2):
            st, solved, _ = sag_pose(P[j, 0], P[j, 1], P[j, 2], Rb[j], bounds, po, sc, redundant)
            if attempt == 0:
                ok = solved
                if st != SAG_OK or ok:
                    break
                bounds = free
            elif st == SAG_OK and not solved:
                st = SAG_NO_TENSIONS
        out.status[j] = st
        out.feasible[j] = 1 if ok else 0
        for i in range(m):
            # sag_pose may leave its scratch in the outputs when it gives up: NaN unless solved
            out.tensions[j, i] = po.t[i] if solved else math.nan
            out.outlet[j, i] = po.outlet[i] if solved else math.nan
            out.L0[j, i] = po.L0[i] if solved else math.nan
            out.sag[j, i] = po.sag[i] if solved else math.nan
            out.lengths[j, i] = po.lengths[i]


_SAMPLES_BLOCK = RowBlock(_samples_loop, lambda P, Rb, robot, *rest: (robot.cables.rows.shape[0],
                                                                      robot.A.shape[0], 1),
                          buffers=_sample_buffers)
