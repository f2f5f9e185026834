"""Grid and point sweeps (blocks of poses on threads, :mod:`cdpr_design.kernels.parallel`)."""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import njit, njit_folded
from cdpr_design.kernels.frame_loads import add_pose, empty_envelope, merge_envelope
from cdpr_design.kernels.geometry import grid_index, next_grid_index, structure_matrix, structure_matrix_pulley
from cdpr_design.kernels.hsm_small import facets_one, facets_two
from cdpr_design.kernels.pose import (ROW_EMPTY, ROW_POSE, PoseBlock, raise_floor, rows_any, rows_small,
                                      rows_square)
from cdpr_design.kernels.tension_qp import line_projection, plane_projection
from cdpr_design.kernels.interference import Clearance, ClearanceScratch, interference_pose
from cdpr_design.kernels.parallel import run_blocks


#: A grid sweep's poses: flat index ``start`` of row 0 (C order over x, y, z), the grid's ``lower``
#: corner and ``step`` (3,) [m] and ``shape`` (3,) int64, the rotated attachments ``Rb`` (m, 3) [m];
#: ``P`` (k, 3) [m]: explicit positions at the same orientation instead of the grid's (row j is
#: ``P[j]``; ``start``, ``lower``, ``step`` and ``shape`` unused), or (0, 3), the default, for the
#: grid.  One compiled loop serves both: the grid sweep and the evaluation of points between grid
#: points (the workspace's boundary).  ``cab`` (m, 13), ``tot`` (5, 3): the envelope of the forces
#: on the frame (:func:`cdpr_design.kernels.frame_loads.frame_load_stats`'s arrays) the sweep raises
#: by its feasible rows, or (0, 13), (0, 3), the default, for none.
GridPoses = namedtuple("GridPoses", "start lower step shape Rb P cab tot",
                       defaults=(np.empty((0, 3)), np.empty((0, 13)), np.empty((0, 3))))


def sweep_grid(poses, statics, wreq, out):
    """Evaluate the grid poses ``poses`` (:class:`GridPoses`: rows 0..count-1 of ``out`` are grid
    poses start .. start + count - 1, C order over x, y, z) of the straight cables ``statics``
    (:class:`~cdpr_design.kernels.pose.Statics`) under the required wrenches ``wreq`` (nv, n) [N, N m]
    (row 0 the nominal one).

    Cable i's lower tension bound at a pose is max(``tmin``[i], ``floor``[i] L_i^2) where
    ``floor``[i] > 0 [N/m^2] (:func:`~cdpr_design.kernels.pose.raise_floor`; zeros: ``tmin``).

    Outputs (:class:`~cdpr_design.kernels.pose.Outputs`, count = ``out.feasible.shape[0]``) are written
    to rows 0..count-1 of ``feasible`` (uint8), ``margin`` [N], ``tensions`` (count, m) [N] and
    ``lengths`` (count, m) [m].  The orientation is fixed: ``poses.Rb`` holds R b_i.  Work is split
    into blocks (:func:`grid_block`) run on threads, each with its own buffers, so no allocation
    happens per pose.  Where ``poses.cab`` has rows, the envelope of the forces on the frame at the
    outlets ``statics.A`` is raised in place by every feasible row with tensions
    (:func:`~cdpr_design.kernels.frame_loads.frame_load_stats`'s forces and arrays, the same values
    as that pass over the rows would give), each block into its own envelope, merged into
    ``poses.cab``, ``poses.tot`` in the rows' order.
    """
    block = grid_block(statics.A.shape[0] - statics.rows.shape[0])
    run_blocks(block, out.feasible.shape[0], poses, statics, out, wreq)
    for _, cab, tot in sorted(block.envelopes, key=lambda e: e[0]):  # in the rows' order: the same
        merge_envelope(poses.cab, poses.tot, cab, tot)  # ties (0.0 and -0.0) kept as one pass would


def grid_block(r: int):
    """The block function computing rows of :func:`sweep_grid` for m - n = ``r``,
    ``block(k0, k1, poses, statics, rows, wreq)``.

    One compiled loop per method: m = n, m - n = 1, m - n = 2 and any other (:func:`_grid_loop_0`,
    :func:`_grid_loop_1`, :func:`_grid_loop_2`, :func:`_grid_loop_any`), chosen here, in Python,
    so that a design compiles only the loop it uses, with only its own margin and QP method
    (:func:`~cdpr_design.kernels.pose.rows_small`).  The block
    (:class:`~cdpr_design.kernels.pose.PoseBlock`) allocates the block's buffers; nothing is
    allocated per pose.
    """
    return _GridBlock(_GRID_LOOPS.get(r, _grid_loop_any))


class _GridBlock(PoseBlock):
    """A :class:`~cdpr_design.kernels.pose.PoseBlock` of :func:`sweep_grid`: where the sweep raises
    a frame-load envelope, each block raises its own (no two threads write one), kept in
    ``envelopes`` as (k0, cab, tot) for :func:`sweep_grid` to merge in the rows' order."""

    def __init__(self, loop):
        super().__init__(loop)
        self.envelopes: list = []

    def __call__(self, k0, k1, src, st, out, w):
        if src.cab.shape[0] == 0:
            super().__call__(k0, k1, src, st, out, w)
            return
        own = src._replace(**dict(zip(("cab", "tot"), empty_envelope(src.cab.shape[0]))))
        super().__call__(k0, k1, own, st, out, w)
        self.envelopes.append((k0, own.cab, own.tot))


@njit_folded
def _grid_position(k, src):
    """(x, y, z) [m] of row ``k``: ``src.P[k]`` where ``src.P`` has rows, else grid index ``src.start + k``."""
    # the bundle's arrays read where they are used, none bound to a name in one branch only, one
    # return: every array's last use is then on the one path out, and numba counts no reference per pose
    if src.P.shape[0] > 0:
        x, y, z = src.P[k, 0], src.P[k, 1], src.P[k, 2]
    else:
        ix, iy, iz = grid_index(src.start + k, src.shape[1], src.shape[2])
        x, y, z = src.lower[0] + ix * src.step[0], src.lower[1] + iy * src.step[1], src.lower[2] + iz * src.step[2]
    return x, y, z


@njit_folded
def _block_loads(k0, k1, src, st, out):
    """Raise ``src.cab``, ``src.tot`` (where they have rows) by the frame loads of rows k0..k1-1 that
    are feasible and have tensions (:func:`~cdpr_design.kernels.frame_loads.add_pose`)."""
    if src.cab.shape[0] == 0:
        return
    feasible, tensions = out.feasible, out.tensions
    for k in range(k0, k1):
        if feasible[k] == 0:
            continue
        finite = True
        for i in range(tensions.shape[1]):
            finite = finite and math.isfinite(tensions[k, i])
        if finite:
            x, y, z = _grid_position(k, src)
            add_pose(x, y, z, k, tensions, st.A, src.Rb, src.cab, src.tot)


@njit_folded
def _place_grid(k, src, st, W, L, lo, w, out):
    """Row ``k``'s pose (grid index ``src.start + k``, or ``src.P[k]`` where ``src.P`` has rows): its
    structure matrix into ``W``, its cable lengths into ``L`` and ``out.lengths[k]`` [m], its lower
    tension bounds into ``lo`` [N] (:func:`~cdpr_design.kernels.pose.raise_floor`).  ROW_EMPTY for a
    cable of zero length."""
    x, y, z = _grid_position(k, src)
    ok = structure_matrix(x, y, z, src.Rb, st.A, st.rows, W, L)
    for i in range(L.shape[0]):
        out.lengths[k, i] = L[i]
    raise_floor(st.tmin, st.floor, L, lo)
    return ROW_POSE if ok else ROW_EMPTY


@njit
def _grid_loop_0(k0, k1, src, st, out, buf):
    """Rows k0..k1-1 of :func:`sweep_grid` for m = n."""
    rows_square(k0, k1, _place_grid, src, st, out, buf)
    _block_loads(k0, k1, src, st, out)


@njit
def _grid_loop_1(k0, k1, src, st, out, buf):
    """Rows k0..k1-1 of :func:`sweep_grid` for m - n = 1."""
    rows_small(k0, k1, _place_grid, src, st, out, buf, facets_one, line_projection)
    _block_loads(k0, k1, src, st, out)


@njit
def _grid_loop_2(k0, k1, src, st, out, buf):
    """Rows k0..k1-1 of :func:`sweep_grid` for m - n = 2."""
    rows_small(k0, k1, _place_grid, src, st, out, buf, facets_two, plane_projection)
    _block_loads(k0, k1, src, st, out)


@njit
def _grid_loop_any(k0, k1, src, st, out, buf):
    """Rows k0..k1-1 of :func:`sweep_grid` for any other m - n (the general margin and QP)."""
    rows_any(k0, k1, _place_grid, src, st, out, buf)
    _block_loads(k0, k1, src, st, out)


#: the grid loop of each redundancy m - n that has its own (:func:`grid_block`)
_GRID_LOOPS = {0: _grid_loop_0, 1: _grid_loop_1, 2: _grid_loop_2}


#: The swivel pulleys of :func:`sweep_points`: each outlet's axis ``K`` (m, 3), reference direction
#: ``Eref`` (m, 3) and radius ``rad`` (m,) [m] (0: a point outlet, :func:`structure_matrix_pulley`).
Pulleys = namedtuple("Pulleys", "K Eref rad")
#: The interference check of :func:`sweep_points` (:func:`interference_pose`): whether to ``check``,
#: the attachments ``Bp`` (m, 3) [m] in the cables' planes, the effector box ``half`` (3,) [m], the
#: cables' radius ``rho`` [m], the frame box ``flo``, ``fhi`` (3,) [m], the motion's ``dim``, the
#: tolerance ``tol`` [m], ``full`` (every pair, not the first hit) and each cable's plane offset
#: ``zoff`` (m,) [m] (planar designs; zeros otherwise).
Interference = namedtuple("Interference", "check Bp half rho flo fhi dim tol full zoff")


def sweep_points(P, Rb, R, statics, wreq, pulleys, check, out, cmask):
    """Evaluate explicit positions ``P`` (count, 3) [m] at one orientation (``R`` (3, 3), ``Rb`` (m, 3)
    the rotated attachments [m]), pulley- and interference-aware.

    Same statics and outputs as :func:`sweep_grid` for rows 0..count-1 (``feasible`` does not
    include interference), plus ``cmask`` (count,) uint8: the :func:`interference_pose` bits when
    ``check.check`` (:class:`Interference`; 0 when not checked).  Outlets with ``pulleys.rad[i]`` > 0
    are swivel pulleys (:class:`Pulleys`, :func:`structure_matrix_pulley`).  ``check.zoff``: each
    cable's plane offset (planar designs; zeros otherwise) added to the z of its free segment's ends
    for the interference check only (``check.Bp`` given in those planes already).
    """
    m = statics.A.shape[0]
    src = Points(P, Rb, R, pulleys.K, pulleys.Eref, pulleys.rad, *check, cmask,
                 np.empty((m, 3)), np.empty((m, 3)), np.zeros((m + 2, m + 2), dtype=np.uint8), np.empty(3),
                 np.empty(3), np.empty(3))
    run_blocks(points_block(m - statics.rows.shape[0]), P.shape[0], src, statics, out, wreq)


#: The poses of :func:`sweep_points` and what their interference check needs (the arguments of the same
#: names), with the work arrays of a block (each block its own, :class:`_PointsBlock`): the cables'
#: exit points ``C`` and free-segment starts ``S0`` (m, 3) [m], the interference ``hits`` (m + 2, m + 2)
#: and three 3-vectors ``s0``, ``s1``, ``cp`` (:func:`~cdpr_design.kernels.interference.interference_pose`).
Points = namedtuple("Points", "P Rb R K Eref rad check Bp half rho flo fhi dim tol full zoff cmask "
                              "C S0 hits s0 s1 cp")


def points_block(r: int):
    """The block computing rows of :func:`sweep_points` for m - n = ``r``: a loop per method, as
    :func:`grid_block`."""
    return _PointsBlock(_POINTS_LOOPS.get(r, _points_loop_any))


class _PointsBlock(PoseBlock):
    """A :class:`~cdpr_design.kernels.pose.PoseBlock` whose poses get the block's own work arrays."""

    def __call__(self, k0, k1, src, st, out, w):
        own = src._replace(C=np.empty_like(src.C), S0=np.empty_like(src.S0), hits=np.zeros_like(src.hits),
                           s0=np.empty(3), s1=np.empty(3), cp=np.empty(3))
        super().__call__(k0, k1, own, st, out, w)


@njit
def _place_points(k, src, st, W, L, lo, w, out):
    """Row ``k``'s pose at ``src.P[k]``: the structure matrix with swivel pulleys into ``W``, the cable
    lengths into ``L`` and ``out.lengths[k]`` [m], the lower tension bounds into ``lo`` [N] (from the
    free lengths, tangent point to attachment), the interference bits into ``src.cmask[k]`` (when
    ``src.check``, else 0).  ROW_EMPTY for a cable of zero length."""
    P, Rb, C, S0, zoff, floor = src.P, src.Rb, src.C, src.S0, src.zoff, st.floor
    lengths = out.lengths
    m = L.shape[0]
    px, py, pz = P[k, 0], P[k, 1], P[k, 2]
    ok = structure_matrix_pulley(px, py, pz, Rb, st.A, src.K, src.Eref, src.rad, st.rows, W, L, C)
    for i in range(m):
        lengths[k, i] = L[i]
        if floor[i] > 0.0:  # the free length (tangent point to attachment), for raise_floor only
            dx = px + Rb[i, 0] - C[i, 0]
            dy = py + Rb[i, 1] - C[i, 1]
            dz = pz + Rb[i, 2] - C[i, 2]
            lo[i] = math.sqrt(dx * dx + dy * dy + dz * dz)
    if src.check:
        for i in range(m):
            S0[i, 0] = px + Rb[i, 0]
            S0[i, 1] = py + Rb[i, 1]
            S0[i, 2] = pz + Rb[i, 2] + zoff[i]
            C[i, 2] += zoff[i]  # the statics are done with C: the row's W and L hold them
        src.cmask[k] = interference_pose(S0, C, src.R, px, py, pz,
                                         Clearance(src.Bp, src.half, src.rho, src.flo, src.fhi, src.dim, src.tol,
                                                   src.full),
                                         ClearanceScratch(src.hits, src.s0, src.s1, src.cp))
    else:
        src.cmask[k] = 0
    raise_floor(st.tmin, floor, lo, lo)
    return ROW_POSE if ok else ROW_EMPTY


@njit
def _points_loop_0(k0, k1, src, st, out, buf):
    rows_square(k0, k1, _place_points, src, st, out, buf)


@njit
def _points_loop_1(k0, k1, src, st, out, buf):
    rows_small(k0, k1, _place_points, src, st, out, buf, facets_one, line_projection)


@njit
def _points_loop_2(k0, k1, src, st, out, buf):
    rows_small(k0, k1, _place_points, src, st, out, buf, facets_two, plane_projection)


@njit
def _points_loop_any(k0, k1, src, st, out, buf):
    rows_any(k0, k1, _place_points, src, st, out, buf)


#: the points loop of each redundancy m - n that has its own (:func:`points_block`)
_POINTS_LOOPS = {0: _points_loop_0, 1: _points_loop_1, 2: _points_loop_2}
