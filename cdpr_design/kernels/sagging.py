"""Inverse statics with heavy, elastic cables: one pose and batched grids.

Each cable is Irvine's elastic catenary (:mod:`cdpr_design.kernels.catenary`)
in the vertical plane through its outlet A and its attachment B.  Its force on
the effector is along the cable's tangent at B, which lies below the chord, so
the structure matrix depends on the tensions.  The tensions are found as a
fixed point (:mod:`cdpr_design.kernels.sag_fixed`):

1. start from the straight-cable minimum-norm tensions t;
2. for every cable, find the shape whose effector-end tension is t_i
   (:func:`~cdpr_design.kernels.cable_shape.cable_for_tension`: the end-force angle and the
   unstretched length by Newton's method) and build the structure matrix W(t) from the
   end-force directions (:mod:`cdpr_design.kernels.sag_shapes`).  A heavy cable cannot pull
   with less than its least tension (:func:`~cdpr_design.kernels.cable_shape.least_tension`,
   the tension of a cable paid out until it pulls least; it is never slack with zero force):
   asked for less, it takes that shape, and its lower bound becomes that tension;
3. stop when W(t) t balances the required wrench to 1e-13 of the forces involved
   (1e-12 where round-off stalls the Newton steps)
   and t no longer changes;
   otherwise take the minimum-norm tensions of W(t) under the bounds shifted
   so that they hold along the whole cable (the largest tension, at the outlet
   for a hanging cable, <= t_max; the smallest >= t_min) and go to 2.

The result is the minimum-norm distribution for the cables' own equilibrium
shapes (for m = n the only one).  Every pose ends with a status
(:data:`SAG_OK` ...): a pose whose shapes did not converge is never reported
with numbers.

The kernels take named bundles: the cables (:data:`~cdpr_design.kernels.sag_shapes.SagCables`),
the robot's statics (:data:`SagRobot`), a grid (:data:`SagGrid`), their outputs
(:data:`GridOutputs`, :data:`PointOutputs`; a pose's :data:`PoseOutputs`) and a block's
scratch (:data:`~cdpr_design.kernels.sag_fixed.SagScratch`), allocated once per block of poses
(:class:`~cdpr_design.kernels.pose.RowBlock`): the loops over poses allocate nothing.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import jitable, njit, njit_folded
from cdpr_design.kernels.catenary import catenary_sag
from cdpr_design.kernels.geometry import grid_index
from cdpr_design.kernels.parallel import run_blocks
from cdpr_design.kernels.pose import RowBlock, eval_general, eval_square_into
from cdpr_design.kernels.sag_fixed import (SAG_NO_CATENARY, SAG_NO_TENSIONS, SAG_NOT_CONVERGED, SAG_OK,
                                           SAG_SINGULAR, distribute, make_sag_scratch, solve)
from cdpr_design.kernels.sag_shapes import CW_H, CW_HI, CW_L0, CW_LO, CW_TA, CW_VB, span, straight_columns

__all__ = ["SAG_NO_CATENARY", "SAG_NO_TENSIONS", "SAG_NOT_CONVERGED", "SAG_OK", "SAG_SINGULAR", "GridOutputs",
           "PoseOutputs", "SagGrid", "SagRobot", "make_pose_outputs", "redundancy", "sag_points",
           "sag_pose", "sag_robot", "sweep_grid_sagging"]

#: The robot's statics as a sagging pose needs them: ``A`` (m, 3) outlets [m], ``cables``
#: (:data:`~cdpr_design.kernels.sag_shapes.SagCables`), ``wreq`` (nv, n) the required wrenches
#: [N, N m] (one row a sample in :func:`~cdpr_design.kernels.sag_path.sag_samples`), ``combos``
#: and ``kind`` as for :func:`cdpr_design.kernels.sweep.sweep_grid`, ``maxit`` the fixed point's
#: iterations allowed.
SagRobot = namedtuple("SagRobot", "A cables wreq combos kind maxit")
#: The positions of a sagging sweep: a grid, ``lower`` (3,) [m], ``step`` (3,) [m], ``shape`` (3,)
#: int64, C order over x, y, z; or, where ``P`` (k, 3) [m] has rows, those explicit positions (row j is
#: ``P[j]``; the grid's fields unused).  One compiled loop serves both (:func:`sweep_grid_sagging`,
#: :func:`sag_points`).
SagGrid = namedtuple("SagGrid", "lower step shape P", defaults=(np.empty((0, 3)),))
#: One pose's per-cable results, each (m,): effector-end tensions ``t`` [N], ``outlet`` tensions
#: [N], unstretched lengths ``L0`` [m], ``sag`` [m] (largest distance from the chord), chord
#: ``lengths`` [m].
PoseOutputs = namedtuple("PoseOutputs", "t outlet L0 sag lengths")
#: Rows of :func:`sweep_grid_sagging` and :func:`sag_points`: ``feasible`` (count,) uint8, ``margin``
#: (count,) [N], ``tensions``, ``lengths``, ``outlet``, ``L0``, ``sag`` (count, m) as
#: :data:`PoseOutputs`, ``status`` (count,) int8, and ``Ws`` (count, n, m) the converged structure
#: matrices (NaN where the shapes are not known), or (0, n, m), the default, for none.
GridOutputs = namedtuple("GridOutputs", "feasible margin tensions lengths outlet L0 sag status Ws",
                         defaults=(np.empty((0, 0, 0)),))


def sag_robot(A, cables, wreq, combos, kind, maxit) -> SagRobot:
    """A :data:`SagRobot` of C-contiguous arrays (the types the kernels are compiled for)."""
    c = np.ascontiguousarray
    return SagRobot(c(A, dtype=float), cables, c(wreq, dtype=float), c(combos), int(kind), int(maxit))


@jitable
def make_pose_outputs(m):
    """The :data:`PoseOutputs` of :func:`sag_pose` for ``m`` cables."""
    return PoseOutputs(np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m))


def redundancy(n: int, m: int):
    """The ``redundant`` argument of the sagging kernels for ``n`` wrench rows and ``m`` cables:
    None for m = n, else m - n.  numba compiles a kernel once per argument type and prunes the
    branches on ``redundant is None`` before typing them, so a square robot's kernels compile
    none of the redundant methods (the QP's and the margin's) and a redundant one's none of the
    square ones."""
    return None if m == n else m - n


@njit_folded
def sag_pose(px, py, pz, Rb, robot, out, sc, redundant):
    """One pose with sagging cables: (status, feasible, margin).

    The effector at (px, py, pz) [m] with its attachments rotated to ``Rb`` (m, 3) [m];
    ``robot`` a :data:`SagRobot`.  Outputs in ``out`` (:data:`PoseOutputs`): effector-end
    tensions, outlet tensions, unstretched lengths and sag (all NaN unless the pose is
    feasible), chord lengths.  ``sc`` is scratch (:func:`~cdpr_design.kernels.sag_fixed.make_sag_scratch`).
    ``redundant``: None where m = n, else m - n (:func:`redundancy`).
    A slack cable (tension at or below :data:`~cdpr_design.kernels.sag_shapes.SLACK` of the
    largest, where its lower bound is 0) pulls along its chord with no force; its outlet tension,
    unstretched length and sag are NaN (undetermined) in a feasible pose.
    The margin is the capacity margin of the converged structure matrix under
    the shifted bounds (NaN unless the status is :data:`SAG_OK`).
    """
    A, cab, wreq = robot.A, robot.cables, robot.wreq
    fx, tq = sc.fixed, sc.tq
    W, cw, lo, hi = fx.W, fx.cw, fx.lo, fx.hi
    t = out.t
    m = A.shape[0]
    for i in range(m):
        t[i] = math.nan
        out.outlet[i] = math.nan
        out.L0[i] = math.nan
        out.sag[i] = math.nan
    if not span(px, py, pz, Rb, A, cab.up, cw, out.lengths):
        W[:, :] = math.nan  # no direction to pull in, and no shapes
        return SAG_SINGULAR, False, math.nan
    straight_columns(Rb, A, px, py, pz, cab.rows, W)
    if distribute(W, wreq[0], cab.tmin, cab.tmax, fx.inf_hi, tq, fx.qp, redundant) == 0:
        W[:, :] = math.nan
        return SAG_NO_TENSIONS, False, math.nan
    status, bounded, _ = solve(tq, Rb, wreq[0], cab, fx, robot.maxit, redundant)
    if status != SAG_OK:
        W[:, :] = math.nan  # the shapes are not known
        return status, False, math.nan
    for i in range(m):
        lo[i] = cw[i, CW_LO]
        hi[i] = cw[i, CW_HI]
    feasible, margin = _evaluate(W, wreq, lo, hi, robot.combos, robot.kind, t, sc.scr, redundant)
    feasible = feasible and bounded == 2
    for i in range(m):
        t[i] = tq[i] if feasible else math.nan
        if feasible and not math.isnan(cw[i, CW_L0]):
            out.outlet[i] = cw[i, CW_TA]
            out.L0[i] = cw[i, CW_L0]
            out.sag[i] = catenary_sag(cw[i, CW_H], cw[i, CW_VB], cw[i, CW_L0], cab.w[i], cab.EA[i])[0]
    return SAG_OK, feasible, margin + 0.0


@njit
def _evaluate(W, wreq, lo, hi, combos, kind, t, scr, redundant):
    """(feasible, margin) of the converged structure matrix ``W`` under the shifted bounds: the
    square case alone where ``redundant`` is None.  A function of its own, not in
    :func:`sag_pose`'s body: numba prunes the branch of an argument that is None before it
    inlines the other's :func:`~cdpr_design.kernels.pose.eval_general`.  Both work in the
    scratch ``scr`` (:func:`~cdpr_design.kernels.hsm.make_scratch`): nothing is allocated."""
    if redundant is None:  # the square case's work arrays from the scratch, as the straight sweeps'
        return eval_square_into(W, wreq, lo, hi, kind, t, scr[4], scr[3], scr[0])
    return eval_general(W, wreq, lo, hi, combos, kind, t, scr, redundant)


def _robot_dims(robot):
    """(n, m, nv) of a :data:`SagRobot`."""
    return robot.cables.rows.shape[0], robot.A.shape[0], robot.wreq.shape[0]


def sag_buffers(n, m, nv):
    """A sagging block's buffers: the pose's :data:`PoseOutputs` and its scratch (numpy: the
    blocks' loops allocate nothing, :class:`~cdpr_design.kernels.pose.RowBlock`)."""
    return make_pose_outputs(m), make_sag_scratch(n, m, nv)


def sweep_grid_sagging(start, count, grid, Rb, robot, out):
    """:func:`cdpr_design.kernels.sweep.sweep_grid` with sagging cables (:func:`sag_pose`).

    Poses ``start`` .. ``start + count - 1`` (flat, C order) of ``grid`` (:data:`SagGrid`) at the
    orientation of ``Rb`` (m, 3) [m], for ``robot`` (:data:`SagRobot`), into rows 0 .. count - 1
    of ``out`` (:data:`GridOutputs`).  Every pose starts from its own straight-cable solution, so
    rows do not depend on the chunking.
    """
    redundant = redundancy(robot.cables.rows.shape[0], robot.A.shape[0])
    run_blocks(_GRID_BLOCK, count, start, grid, Rb, robot, out, redundant, grain=16)


@njit_folded
def _sag_position(k, start, grid):
    """(x, y, z) [m] of row ``k``: ``grid.P[k]`` where ``grid.P`` has rows, else grid index ``start + k``."""
    # the bundle's arrays read where they are used, none bound to a name in one branch only, one
    # return (as the straight sweep's grid position): numba counts no reference per pose
    if grid.P.shape[0] > 0:
        x, y, z = grid.P[k, 0], grid.P[k, 1], grid.P[k, 2]
    else:
        ix, iy, iz = grid_index(start + k, grid.shape[1], grid.shape[2])
        x, y, z = (grid.lower[0] + ix * grid.step[0], grid.lower[1] + iy * grid.step[1],
                   grid.lower[2] + iz * grid.step[2])
    return x, y, z


@njit
def _grid_loop(k0, k1, start, grid, Rb, robot, out, redundant, po, sc):
    """Rows k0..k1-1 of :func:`sweep_grid_sagging` or :func:`sag_points` (``redundant``:
    :func:`redundancy`), with the block's buffers (:func:`sag_buffers`)."""
    m = robot.A.shape[0]
    for k in range(k0, k1):
        x, y, z = _sag_position(k, start, grid)
        st, f, mg = sag_pose(x, y, z, Rb, robot, po, sc, redundant)
        store_row(out, k, st, f, mg, po, m)
        if out.Ws.shape[0] > 0:
            for r in range(sc.fixed.W.shape[0]):
                for i in range(m):
                    out.Ws[k, r, i] = sc.fixed.W[r, i]


@njit
def store_row(out, k, st, f, mg, po, m):
    """Write row ``k`` of ``out`` (:data:`GridOutputs`, or the rows of the sagging interference checks):
    the pose's status ``st``, feasibility ``f``, margin ``mg`` [N] and its :data:`PoseOutputs` ``po``
    (tensions, lengths, outlet tensions, unstretched lengths, sag) of its ``m`` cables."""
    out.status[k] = st
    out.feasible[k] = 1 if f else 0
    out.margin[k] = mg
    for i in range(m):
        out.tensions[k, i] = po.t[i]
        out.lengths[k, i] = po.lengths[i]
        out.outlet[k, i] = po.outlet[i]
        out.L0[k, i] = po.L0[i]
        out.sag[k, i] = po.sag[i]


_GRID_BLOCK = RowBlock(_grid_loop, lambda start, grid, Rb, robot, *rest: _robot_dims(robot), buffers=sag_buffers)


def sag_points(P, Rb, robot, structures: bool = True):
    """:func:`sag_pose` at positions ``P`` (k, 3) [m] (one orientation, in ``Rb`` (m, 3) [m]) for
    ``robot`` (:data:`SagRobot`): the rows as :func:`sweep_grid_sagging` writes them, a new
    :data:`GridOutputs`, with the converged structure matrices ``Ws`` (k, n, m) where
    ``structures`` (for the sizing, which needs them at each task pose).  The same compiled loop
    as the grid's."""
    n, m = robot.cables.rows.shape[0], robot.A.shape[0]
    k = P.shape[0]
    out = GridOutputs(np.empty(k, dtype=np.uint8), np.empty(k), *(np.empty((k, m)) for _ in range(5)),
                      np.empty(k, dtype=np.int8), np.empty((k if structures else 0, n, m)))
    grid = SagGrid(np.zeros(3), np.zeros(3), np.ones(3, dtype=np.int64), np.ascontiguousarray(P, dtype=float))
    run_blocks(_GRID_BLOCK, k, 0, grid, Rb, robot, out, redundancy(n, m), grain=16)
    return out
