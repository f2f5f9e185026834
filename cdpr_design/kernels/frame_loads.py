"""The envelope of the forces straight cables from point outlets put on the frame, over poses at
one orientation, in one pass (the numpy formulation of :mod:`cdpr_design.workspaces.frame_loads`
makes a dozen passes over (m, 3, k) temporaries): over a chunk of rows (:func:`frame_load_stats`),
or pose by pose inside a sweep's own loop (:func:`add_pose`, the grid sweep's blocks:
:func:`cdpr_design.kernels.sweep.sweep_grid`), each block into its own envelope, merged after
(:func:`merge_envelope`).

Compiled with :data:`~cdpr_design.kernels._jit.njit` (cached, nogil, numpy's error model).
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.kernels._jit import njit, njit_folded, njit_inline

#: Columns of the per-cable statistics ``cab``: largest |F| [N], least and largest F (x, y, z)
#: [N], least and largest unit direction (x, y, z).
CAB_COLUMNS = 13
#: The columns of ``cab`` that hold a largest value (the others a least one).
CAB_MAX = np.array([0, 4, 5, 6, 10, 11, 12])
CAB_MIN = np.array([1, 2, 3, 7, 8, 9])


def empty_envelope(m: int) -> tuple[np.ndarray, np.ndarray]:
    """(``cab`` (m, 13), ``tot`` (5, 3)): the envelope of no pose (:func:`frame_load_stats`'s
    arrays before the first: least values +inf, largest -inf, the count 0)."""
    cab = np.empty((m, CAB_COLUMNS))
    cab[:, CAB_MAX] = -np.inf
    cab[:, CAB_MIN] = np.inf
    tot = np.empty((5, 3))
    tot[[0, 2]], tot[[1, 3]], tot[4] = np.inf, -np.inf, (-np.inf, -np.inf, 0.0)
    return cab, tot


def merge_envelope(cab: np.ndarray, tot: np.ndarray, cab2: np.ndarray, tot2: np.ndarray) -> None:
    """Widen the envelope ``cab``, ``tot`` in place by another one, ``cab2``, ``tot2``, of the poses
    after its own: the least of the least values, the largest of the largest (of two equal ones,
    such as 0.0 and -0.0, the first, as :func:`frame_load_stats` keeps it), the sum of the counts.
    Exact: the envelope of consecutive blocks merged in their order is that of one pass."""
    cab[:, CAB_MAX] = _larger(cab[:, CAB_MAX], cab2[:, CAB_MAX])
    cab[:, CAB_MIN] = _smaller(cab[:, CAB_MIN], cab2[:, CAB_MIN])
    tot[[0, 2]] = _smaller(tot[[0, 2]], tot2[[0, 2]])
    tot[[1, 3]] = _larger(tot[[1, 3]], tot2[[1, 3]])
    tot[4, :2] = _larger(tot[4, :2], tot2[4, :2])
    tot[4, 2] += tot2[4, 2]


def _larger(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """b where it is larger than a, else a (the first of two equal values, as the kernels' ``max``;
    numpy's ``fmax`` on arrays may take either)."""
    return np.where(b > a, b, a)


def _smaller(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """b where it is smaller than a, else a (the first of two equal values, as the kernels' ``min``)."""
    return np.where(b < a, b, a)


@njit
def frame_load_stats(P, ok, t, A, Rb, cab, tot):
    """Raise the frame-load envelope by the poses ``P`` (k, 3) [m] where ``ok`` (k,) uint8 is 1,
    with tensions ``t`` (k, m) [N], outlets ``A`` (m, 3) [m] and rotated attachments ``Rb`` (m, 3)
    [m].  The force at outlet i is F_i = t_i u_i, u_i the unit vector from A_i to the attachment
    P + Rb_i.

    In place: ``cab`` (m, 13) per cable (:data:`CAB_COLUMNS`: max |F|, min F x y z, max F x y z,
    min u x y z, max u x y z); ``tot`` (5, 3): rows min and max of the total force sum_i F_i
    [N], min and max of its moment sum_i A_i x F_i [N m] about the origin, and in row 4 the
    largest |total force|, the largest |moment| and the count of poses added.  A cable of zero
    length contributes nothing at that pose.
    """
    for k in range(P.shape[0]):
        if ok[k] != 0:
            add_pose(P[k, 0], P[k, 1], P[k, 2], k, t, A, Rb, cab, tot)


@njit_folded
def add_pose(x, y, z, k, t, A, Rb, cab, tot):
    """Raise the envelope ``cab``, ``tot`` (:func:`frame_load_stats`) by the pose at (x, y, z) [m]
    with the tensions of row ``k`` of ``t`` (k, m) [N] (inlined into its callers, with their
    options: the same arithmetic in every one)."""
    m = A.shape[0]
    fx = fy = fz = 0.0
    mx = my = mz = 0.0
    for i in range(m):
        dx = x + Rb[i, 0] - A[i, 0]
        dy = y + Rb[i, 1] - A[i, 1]
        dz = z + Rb[i, 2] - A[i, 2]
        L = math.sqrt(dx * dx + dy * dy + dz * dz)
        if L <= 0.0:
            continue
        ux, uy, uz = dx / L, dy / L, dz / L
        ti = t[k, i]
        gx, gy, gz = ti * ux, ti * uy, ti * uz
        cab[i, 0] = max(cab[i, 0], abs(ti))
        _widen(cab, i, 1, i, 4, gx, gy, gz)
        _widen(cab, i, 7, i, 10, ux, uy, uz)
        fx += gx
        fy += gy
        fz += gz
        mx += A[i, 1] * gz - A[i, 2] * gy
        my += A[i, 2] * gx - A[i, 0] * gz
        mz += A[i, 0] * gy - A[i, 1] * gx
    _widen(tot, 0, 0, 1, 0, fx, fy, fz)
    _widen(tot, 2, 0, 3, 0, mx, my, mz)
    tot[4, 0] = max(tot[4, 0], math.sqrt(fx * fx + fy * fy + fz * fz))
    tot[4, 1] = max(tot[4, 1], math.sqrt(mx * mx + my * my + mz * mz))
    tot[4, 2] += 1.0


@njit_inline
def _widen(M, r_lo, c_lo, r_hi, c_hi, x, y, z):
    """Lower ``M[r_lo, c_lo:c_lo + 3]`` to (x, y, z) where they are smaller, and raise
    ``M[r_hi, c_hi:c_hi + 3]`` to them where they are larger (an envelope's least and largest
    vector, componentwise)."""
    M[r_lo, c_lo] = min(M[r_lo, c_lo], x)
    M[r_lo, c_lo + 1] = min(M[r_lo, c_lo + 1], y)
    M[r_lo, c_lo + 2] = min(M[r_lo, c_lo + 2], z)
    M[r_hi, c_hi] = max(M[r_hi, c_hi], x)
    M[r_hi, c_hi + 1] = max(M[r_hi, c_hi + 1], y)
    M[r_hi, c_hi + 2] = max(M[r_hi, c_hi + 2], z)
