"""Grid and point sweeps (blocks of poses on threads, :mod:`cdpr_design.kernels.parallel`) and
per-chunk statistics."""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.kernels._jit import njit, njit_inline, njit_noref
from cdpr_design.kernels.linalg import RANK_TOL
from cdpr_design.kernels.geometry import grid_index, next_grid_index, structure_matrix, structure_matrix_pulley
from cdpr_design.kernels.pointers import PointerBlock
from cdpr_design.kernels.pose import RowBlock, eval_row, eval_row_small, raise_floor, row_buffers
from cdpr_design.kernels.interference import interference_pose
from cdpr_design.kernels.parallel import run_blocks


def sweep_grid(start, count, lower, step, shape, Rb, A, rows, wreq, tmin, tmax, floor, combos,
               kind, feasible, margin, tensions, lengths):
    """Evaluate ``count`` grid poses from flat index ``start`` (C order over x, y, z).

    Cable i's lower tension bound at a pose is max(``tmin``[i], ``floor``[i] L_i^2) where
    ``floor``[i] > 0 [N/m^2] (:func:`~cdpr_design.kernels.pose.raise_floor`; zeros: ``tmin``).

    Outputs are written to rows 0..count-1 of ``feasible`` (uint8), ``margin``,
    ``tensions`` (count, m) and ``lengths`` (count, m).  The orientation is
    fixed: ``Rb`` holds R b_i.  Work is split into blocks (:func:`grid_block`)
    run on threads, each with its own scratch arrays, so no allocation happens per pose.
    """
    run_blocks(grid_block(A.shape[0] - rows.shape[0]), count, start, lower, step, shape, Rb, A, rows, wreq,
               tmin, tmax, floor, combos, kind, feasible, margin, tensions, lengths)


def grid_block(r: int):
    """The block function computing rows k0..k1-1 of :func:`sweep_grid` for m - n = ``r``.

    One loop per redundancy: m = n (:func:`_grid_loop_0`), m - n = 1 or 2 (:func:`_grid_loop_small`,
    one loop for both: it is given the pose's functions as pointers,
    :mod:`cdpr_design.kernels.pointers`, and so compiles without them, alone, and once for every
    such design), and any other (:func:`_grid_loop_any`).  Chosen here, in Python, so that a design
    compiles only the loop it uses, each with only its own margin and QP method
    (:func:`~cdpr_design.kernels.pose.eval_general`), which is also faster a pose than one kernel
    for every r (docs/performance.md).

    The block (:class:`~cdpr_design.kernels.pose.RowBlock`,
    :class:`~cdpr_design.kernels.pointers.PointerBlock`) allocates the block's buffers
    (:func:`~cdpr_design.kernels.pose.row_buffers`) and hands them to its loop over the poses,
    compiled without reference counting (:data:`~cdpr_design.kernels._jit.njit_noref`): every
    array a pose's code binds or passes on (the scratch tuple alone holds 31) otherwise costs an
    atomic increment and decrement per pose.
    """
    if r in (1, 2):
        return PointerBlock(_grid_loop_small, _grid_parts)
    return RowBlock(_grid_loop_0 if r == 0 else _grid_loop_any, _grid_dims)


def _grid_dims(*args):
    """(n, m, nv) of a grid block's arguments (the first three of :func:`_grid_parts`)."""
    return _grid_parts(*args)[:3]


def _grid_parts(start, lower, step, shape, Rb, A, rows, wreq, tmin, tmax, *rest):
    """(n, m, nv, wreq, tmax) of a grid block's arguments."""
    return rows.shape[0], A.shape[0], wreq.shape[0], wreq, tmax


@njit_noref
def _grid_loop_small(factor, null, setup, facets, project, structure, k0, k1, start, lower, step, shape, Rb, A,
                     rows, wreq, tmin, tmax, floor, combos, kind, feasible, margin, tensions, lengths, W, t, L, lo,
                     scr):
    """Rows k0..k1-1 of :func:`sweep_grid` (grid poses start+k0 .. start+k1-1) for m - n = 1 or 2,
    with the pose's six functions given (:func:`~cdpr_design.kernels.pose.eval_small`'s five and
    the structure matrix, :mod:`~cdpr_design.kernels.pointers`) and the block's buffers
    (:func:`~cdpr_design.kernels.pose.row_buffers`, the scratch as its
    :func:`~cdpr_design.kernels.pose.small_scratch`)."""
    ix, iy, iz = grid_index(start + k0, shape[1], shape[2])
    for k in range(k0, k1):
        ok, ix, iy, iz = _grid_pose(k, ix, iy, iz, lower, step, shape, Rb, A, rows, tmin, floor, W, L, lo, lengths,
                                    structure)
        eval_row_small(k, ok, W, wreq, lo, tmax, kind, t, scr, feasible, margin, tensions,
                       factor, null, setup, facets, project)


@njit_noref
def _grid_loop_0(k0, k1, start, lower, step, shape, Rb, A, rows, wreq, tmin, tmax, floor, combos, kind,
                 feasible, margin, tensions, lengths, W, t, L, lo, scr):
    """:func:`_grid_loop_small` for m = n."""
    ix, iy, iz = grid_index(start + k0, shape[1], shape[2])
    for k in range(k0, k1):
        ok, ix, iy, iz = _grid_pose(k, ix, iy, iz, lower, step, shape, Rb, A, rows, tmin, floor, W, L, lo, lengths,
                                    structure_matrix)
        eval_row(k, ok, W, wreq, lo, tmax, combos, kind, t, scr, feasible, margin, tensions, 0)


@njit_noref
def _grid_loop_any(k0, k1, start, lower, step, shape, Rb, A, rows, wreq, tmin, tmax, floor, combos, kind,
                   feasible, margin, tensions, lengths, W, t, L, lo, scr):
    """:func:`_grid_loop_small` for any other m - n (the general margin and QP)."""
    r = A.shape[0] - rows.shape[0]
    ix, iy, iz = grid_index(start + k0, shape[1], shape[2])
    for k in range(k0, k1):
        ok, ix, iy, iz = _grid_pose(k, ix, iy, iz, lower, step, shape, Rb, A, rows, tmin, floor, W, L, lo, lengths,
                                    structure_matrix)
        eval_row(k, ok, W, wreq, lo, tmax, combos, kind, t, scr, feasible, margin, tensions, r)


@njit_inline
def _grid_pose(k, ix, iy, iz, lower, step, shape, Rb, A, rows, tmin, floor, W, L, lo, lengths, structure):
    """Row ``k``'s grid pose, at grid indices (ix, iy, iz): its structure matrix into ``W`` (by
    ``structure``: :func:`~cdpr_design.kernels.geometry.structure_matrix` or a pointer to it), its
    cable lengths into ``L`` and ``lengths[k]`` [m], its lower tension bounds into ``lo`` [N]
    (:func:`~cdpr_design.kernels.pose.raise_floor`).  Returns (ok, the next pose's indices): ok
    False for a cable of zero length.  The grid's indices are counted up, not divided per pose."""
    px = lower[0] + ix * step[0]
    py = lower[1] + iy * step[1]
    pz = lower[2] + iz * step[2]
    ix, iy, iz = next_grid_index(ix, iy, iz, shape[1], shape[2])
    ok = structure(px, py, pz, Rb, A, rows, W, L)
    for i in range(A.shape[0]):
        lengths[k, i] = L[i]
    raise_floor(tmin, floor, L, lo)
    return ok, ix, iy, iz


def sweep_grid_planar2(start, count, lower, step, shape, Rb, A, wreq, tmin, tmax, floor,
                       feasible, margin, tensions, lengths):
    """:func:`sweep_grid` specialised to two cables and two wrench rows (2T, m = n = 2).

    The seed paper's robot: everything inlined in closed form.  With
    u_i the unit cable vectors, det = u1x u2y - u2x u1y,
    t1 = (w_x u2y - w_y u2x) / det, t2 = (u1x w_y - u1y w_x) / det
    (algorithms.md; paper eq. 6-9), and the capacity margin is
    min_i min(t_i - t_min,i, t_max,i - t_i) / ||row_i(W^-1)||, t_min,i raised to ``floor``[i] L_i^2
    where ``floor``[i] > 0 (as :func:`~cdpr_design.kernels.pose.raise_floor`).
    Only the nominal wrench (row 0 of ``wreq``) is evaluated, plus the other
    rows for the margin when there are several (wrench-feasible sweeps).
    Same outputs as :func:`sweep_grid`.
    """
    run_blocks(planar2_block, count, start, lower, step, shape, Rb, A, wreq, tmin, tmax, floor,
               feasible, margin, tensions, lengths, grain=4096)


@njit_noref
def planar2_block(k0, k1, start, lower, step, shape, Rb, A, wreq, tmin, tmax, floor, feasible, margin, tensions,
                  lengths):
    """Rows k0..k1-1 of :func:`sweep_grid_planar2`."""
    ny = shape[1]
    nz = shape[2]
    nv = wreq.shape[0]
    a0x = A[0, 0] - Rb[0, 0]
    a0y = A[0, 1] - Rb[0, 1]
    a1x = A[1, 0] - Rb[1, 0]
    a1y = A[1, 1] - Rb[1, 1]
    # scalars hoisted out of the loop: the outputs could alias these arrays,
    # which would otherwise force a reload per pose
    w0 = wreq[0, 0]
    w1 = wreq[0, 1]
    tm0 = tmin[0]
    tm1 = tmin[1]
    c0 = floor[0]
    c1 = floor[1]
    tx0 = tmax[0]
    tx1 = tmax[1]
    ix, iy, iz = grid_index(start + k0, ny, nz)
    for k in range(k0, k1):
        px = lower[0] + ix * step[0]
        py = lower[1] + iy * step[1]
        ix, iy, iz = next_grid_index(ix, iy, iz, ny, nz)
        lx0 = a0x - px
        ly0 = a0y - py
        lx1 = a1x - px
        ly1 = a1y - py
        L0 = math.sqrt(lx0 * lx0 + ly0 * ly0)
        L1 = math.sqrt(lx1 * lx1 + ly1 * ly1)
        lengths[k, 0] = L0
        lengths[k, 1] = L1
        tn0 = max(tm0, c0 * L0 * L0) if c0 > 0.0 else tm0
        tn1 = max(tm1, c1 * L1 * L1) if c1 > 0.0 else tm1
        u0x = u0y = u1x = u1y = det = 0.0  # a zero-length cable: no structure matrix
        if L0 > 1e-12 and L1 > 1e-12:
            u0x = lx0 / L0
            u0y = ly0 / L0
            u1x = lx1 / L1
            u1y = ly1 / L1
            det = u0x * u1y - u1x * u0y
        if abs(det) <= RANK_TOL:
            feasible[k] = 0
            margin[k] = np.nan
            tensions[k, 0] = np.nan
            tensions[k, 1] = np.nan
            continue
        inv = 1.0 / det
        i00 = u1y * inv
        i01 = -u1x * inv
        i10 = -u0y * inv
        i11 = u0x * inv
        r0 = math.sqrt(i00 * i00 + i01 * i01)
        r1 = math.sqrt(i10 * i10 + i11 * i11)
        t0 = i00 * w0 + i01 * w1
        t1 = i10 * w0 + i11 * w1
        s = min(min(t0 - tn0, tx0 - t0) / r0, min(t1 - tn1, tx1 - t1) / r1)
        inb = s >= 0.0
        if nv > 1:
            for v in range(1, nv):
                q0 = i00 * wreq[v, 0] + i01 * wreq[v, 1]
                q1 = i10 * wreq[v, 0] + i11 * wreq[v, 1]
                s = min(s, min(min(q0 - tn0, tx0 - q0) / r0, min(q1 - tn1, tx1 - q1) / r1))
        margin[k] = s + 0.0  # -0.0 -> 0.0 (as the numpy engine)
        feasible[k] = 1 if s >= 0.0 else 0
        tensions[k, 0] = t0 if inb else np.nan
        tensions[k, 1] = t1 if inb else np.nan


@njit_noref
def chunk_stats(feasible, margin, tensions, count, tpeak):
    """Feasible count and margin extremes over the feasible rows 0..count-1; ``tpeak`` (m) is
    raised to each cable's largest feasible tension.  Returns (count, min, max) (-0.0 is returned as
    0.0).  One pass on one thread: a millisecond for 150,000 rows, against the sweep's tenths of a second."""
    m = tensions.shape[1]
    nf = 0
    lo = np.inf
    hi = -np.inf
    for k in range(count):
        if feasible[k]:
            nf += 1
            v = margin[k]
            if v < lo:
                lo = v
            if v > hi:
                hi = v
            for i in range(m):
                t = tensions[k, i]
                if t > tpeak[i]:
                    tpeak[i] = t
    return nf, lo + 0.0, hi + 0.0


def compile_chunk_stats() -> None:
    """Compile (or load from numba's cache) :func:`chunk_stats` for the types the sweeps give it
    (C-contiguous uint8, float64 and (rows, m) float64 arrays, an int): what a first run's other
    process compiles while this one compiles the sweep's loop (:mod:`cdpr_design.kernels.warm`)."""
    chunk_stats(np.zeros(1, dtype=np.uint8), np.zeros(1), np.zeros((1, 1)), 1, np.zeros(1))


def sweep_points(P, Rb, R, A, K, Eref, rad, rows, wreq, tmin, tmax, floor, combos, kind,
                 check, Bp, half, rho, flo, fhi, dim, tol, full, zoff,
                 feasible, margin, tensions, lengths, cmask):
    """Evaluate explicit positions ``P`` (count, 3) at one orientation, pulley- and interference-aware.

    Same outputs as :func:`sweep_grid` for rows 0..count-1 (statics only:
    ``feasible`` does not include interference), plus ``cmask`` (uint8): the
    :func:`interference_pose` bits when ``check`` (0 when not checked).
    Outlets with ``rad[i]`` > 0 are swivel pulleys (:func:`structure_matrix_pulley`).  ``zoff`` (m,)
    [m]: each cable's plane offset (planar designs; zeros otherwise) added to the z of its free
    segment's ends for the interference check only (``Bp`` given in those planes already).
    """
    run_blocks(points_block, P.shape[0], P, Rb, R, A, K, Eref, rad, rows, wreq, tmin, tmax, floor, combos, kind,
               check, Bp, half, rho, flo, fhi, dim, tol, full, zoff, feasible, margin, tensions, lengths, cmask)


@njit
def points_block(k0, k1, P, Rb, R, A, K, Eref, rad, rows, wreq, tmin, tmax, floor, combos, kind,
                 check, Bp, half, rho, flo, fhi, dim, tol, full, zoff, feasible, margin, tensions, lengths, cmask):
    """Rows k0..k1-1 of :func:`sweep_points`: the block's buffers, then :func:`_points_loop`."""
    m = A.shape[0]
    W, t, L, lo, scr = row_buffers(rows.shape[0], m, wreq.shape[0])
    _points_loop(k0, k1, P, Rb, R, A, K, Eref, rad, rows, wreq, tmin, tmax, floor, combos, kind,
                 check, Bp, half, rho, flo, fhi, dim, tol, full, zoff, feasible, margin, tensions, lengths, cmask,
                 W, t, L, lo, scr, np.empty((m, 3)), np.empty((m, 3)), np.zeros((m + 2, m + 2), dtype=np.uint8),
                 np.empty(3), np.empty(3), np.empty(3))


@njit_noref
def _points_loop(k0, k1, P, Rb, R, A, K, Eref, rad, rows, wreq, tmin, tmax, floor, combos, kind,
                 check, Bp, half, rho, flo, fhi, dim, tol, full, zoff, feasible, margin, tensions, lengths, cmask,
                 W, t, L, lo, scr, C, S0, hits, s0, s1, cp):
    """The poses of :func:`points_block` with its buffers (no reference counting, see :func:`grid_block`)."""
    n = rows.shape[0]
    m = A.shape[0]
    for k in range(k0, k1):
        px, py, pz = P[k, 0], P[k, 1], P[k, 2]
        ok = structure_matrix_pulley(px, py, pz, Rb, A, K, Eref, rad, rows, W, L, C)
        for i in range(m):
            lengths[k, i] = L[i]
            if floor[i] > 0.0:  # the free length (tangent point to attachment), for raise_floor only
                dx = px + Rb[i, 0] - C[i, 0]
                dy = py + Rb[i, 1] - C[i, 1]
                dz = pz + Rb[i, 2] - C[i, 2]
                lo[i] = math.sqrt(dx * dx + dy * dy + dz * dz)
        if check:
            for i in range(m):
                S0[i, 0] = px + Rb[i, 0]
                S0[i, 1] = py + Rb[i, 1]
                S0[i, 2] = pz + Rb[i, 2] + zoff[i]
                C[i, 2] += zoff[i]  # the statics are done with C: the row's W and L hold them
            cmask[k] = interference_pose(S0, C, Bp, R, px, py, pz, half, rho, flo, fhi, dim,
                                         tol, full, hits, s0, s1, cp)
        else:
            cmask[k] = 0
        eval_row(k, ok, W, wreq, raise_floor(tmin, floor, lo, lo), tmax, combos, kind, t, scr, feasible, margin,
                 tensions, m - n)
