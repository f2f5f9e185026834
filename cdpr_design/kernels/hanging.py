"""The statics of an effector at positions each with its own orientation (a hanging effector's).

:func:`eval_rotated` is the grid sweep's evaluation (:func:`cdpr_design.kernels.sweep.sweep_grid`:
feasibility, capacity margin, tensions, lengths) at explicit positions, each at the rotation the
effector hangs in there (:func:`cdpr_design.statics.hanging.at_positions.hanging_orientations`
finds it), in blocks of rows on threads.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import njit
from cdpr_design.kernels.parallel import run_blocks
from cdpr_design.kernels.geometry import rotate_attachments, structure_matrix
from cdpr_design.kernels.hsm_small import facets_one, facets_two
from cdpr_design.kernels.pose import (ROW_DONE, ROW_EMPTY, ROW_POSE, PoseBlock, raise_floor, rows_any,
                                      rows_small, rows_square)
from cdpr_design.kernels.tension_qp import line_projection, plane_projection


def eval_rotated(P, R, B, statics, wreq, out):
    """Feasibility, capacity margin and tensions at positions each with its own orientation.

    :func:`cdpr_design.kernels.sweep.sweep_grid` for explicit positions ``P`` (k, 3) [m] at
    rotations ``R`` (k, 3, 3) (a hanging effector's), with the required wrenches ``wreq``
    (k, nv, n) [N, N m] of each pose; ``B`` (m, 3) the attachments in platform coordinates;
    ``statics`` the straight cables (:class:`~cdpr_design.kernels.pose.Statics`).  A pose whose
    rotation is NaN (the effector cannot hang there) gets feasible 0 and NaN margin, tensions and
    lengths.  Lower tension bounds and outputs (:class:`~cdpr_design.kernels.pose.Outputs`) as
    :func:`~cdpr_design.kernels.sweep.sweep_grid`.
    """
    run_blocks(rotated_block(statics.A.shape[0] - statics.rows.shape[0]), P.shape[0],
               Rotated(P, R, B, np.empty_like(B), wreq), statics, out, wreq[0])


#: The poses of :func:`eval_rotated`: positions ``P`` (k, 3) [m], rotations ``R`` (k, 3, 3), the
#: attachments ``B`` (m, 3) [m] in platform coordinates, the rotated ones ``Rb`` (m, 3) [m] (work:
#: each block gets its own, :class:`_RotatedBlock`), the required wrenches ``wreq`` (k, nv, n) [N, N m].
Rotated = namedtuple("Rotated", "P R B Rb wreq")


def rotated_block(r: int):
    """The block computing rows of :func:`eval_rotated` for m - n = ``r``, chosen here in Python as
    :func:`cdpr_design.kernels.sweep.grid_block` does: m = n, 1, 2 and any other r each a loop of
    its own (compiled with only its own margin and QP method)."""
    return _RotatedBlock(_ROTATED_LOOPS.get(r, _rotated_loop_any))


class _RotatedBlock(PoseBlock):
    """A :class:`~cdpr_design.kernels.pose.PoseBlock` whose poses get the block's own rotated attachments."""

    def __call__(self, k0, k1, src, st, out, w):
        super().__call__(k0, k1, src._replace(Rb=np.empty_like(src.B)), st, out, w)


@njit
def _place_rotated(k, src, st, W, L, lo, w, out):
    """Row ``k``'s pose at its own rotation ``src.R[k]``: the rotated attachments into ``src.Rb``, the
    structure matrix into ``W``, the cable lengths into ``L`` and ``out.lengths[k]`` [m], the lower
    tension bounds into ``lo`` [N], the pose's required wrenches into ``w``.  ROW_DONE where the
    effector cannot hang there (its rotation NaN: the row is then written infeasible, its margin,
    tensions and lengths NaN), ROW_EMPTY for a cable of zero length."""
    lengths = out.lengths
    m = lengths.shape[1]
    R, P, Rb, wreq = src.R, src.P, src.Rb, src.wreq
    if not np.isfinite(R[k, 0, 0]):
        out.feasible[k] = 0
        out.margin[k] = np.nan
        for i in range(m):
            out.tensions[k, i] = np.nan
            lengths[k, i] = np.nan
        return ROW_DONE
    rotate_attachments(R[k], src.B, Rb)
    ok = structure_matrix(P[k, 0], P[k, 1], P[k, 2], Rb, st.A, st.rows, W, L)
    for i in range(m):
        lengths[k, i] = L[i]
    raise_floor(st.tmin, st.floor, L, lo)
    for v in range(w.shape[0]):
        for j in range(w.shape[1]):
            w[v, j] = wreq[k, v, j]
    return ROW_POSE if ok else ROW_EMPTY


@njit
def _rotated_loop_0(k0, k1, src, st, out, buf):
    rows_square(k0, k1, _place_rotated, src, st, out, buf)


@njit
def _rotated_loop_1(k0, k1, src, st, out, buf):
    rows_small(k0, k1, _place_rotated, src, st, out, buf, facets_one, line_projection)


@njit
def _rotated_loop_2(k0, k1, src, st, out, buf):
    rows_small(k0, k1, _place_rotated, src, st, out, buf, facets_two, plane_projection)


@njit
def _rotated_loop_any(k0, k1, src, st, out, buf):
    rows_any(k0, k1, _place_rotated, src, st, out, buf)


#: the rotated loop of each redundancy m - n that has its own (:func:`rotated_block`)
_ROTATED_LOOPS = {0: _rotated_loop_0, 1: _rotated_loop_1, 2: _rotated_loop_2}
