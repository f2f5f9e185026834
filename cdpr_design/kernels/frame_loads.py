"""The envelope of the forces straight cables from point outlets put on the frame, over a chunk
of poses at one orientation, in one pass (the numpy formulation of
:mod:`cdpr_design.workspaces.frame_loads` makes a dozen passes over (m, 3, k) temporaries).

Compiled with :data:`~cdpr_design.kernels._jit.njit` (cached, nogil, numpy's error model).
"""

from __future__ import annotations

import math

from cdpr_design.kernels._jit import njit, njit_inline

#: Columns of the per-cable statistics ``cab``: largest |F| [N], least and largest F (x, y, z)
#: [N], least and largest unit direction (x, y, z).
CAB_COLUMNS = 13


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
    m = A.shape[0]
    for k in range(P.shape[0]):
        if ok[k] == 0:
            continue
        fx = fy = fz = 0.0
        mx = my = mz = 0.0
        for i in range(m):
            dx = P[k, 0] + Rb[i, 0] - A[i, 0]
            dy = P[k, 1] + Rb[i, 1] - A[i, 1]
            dz = P[k, 2] + Rb[i, 2] - A[i, 2]
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
