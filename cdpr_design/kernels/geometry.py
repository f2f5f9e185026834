"""Kinematics kernels: rotation matrices, structure matrix columns, swivel-pulley exits.

Conventions (docs/spec-format.md): full pose ``[x, y, z, rx, ry, rz]`` [m, rad],
R = Rx(rx) Ry(ry) Rz(rz); cable vector l_i = a_i - (p + R b_i), u_i = l_i / |l_i|
(pulls towards the outlet); structure matrix column i = [u_i ; (R b_i) x u_i][rows].
Pulley conventions: :mod:`cdpr_design.statics.pulley`.
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.kernels._jit import njit, njit_folded, njit_inline


@njit_inline
def grid_index(idx, ny, nz):
    """(ix, iy, iz): the axis indices of flat grid index ``idx`` (C order over x, y, z)."""
    r = idx // nz
    return r // ny, r % ny, idx % nz


@njit_inline
def next_grid_index(ix, iy, iz, ny, nz):
    """The axis indices of the grid pose after (ix, iy, iz) in C order (no division)."""
    iz += 1
    if iz == nz:
        iz = 0
        iy += 1
        if iy == ny:
            iy = 0
            ix += 1
    return ix, iy, iz


@njit
def rotation(rx, ry, rz, R):
    """R = Rx(rx) Ry(ry) Rz(rz) written into ``R`` (3, 3)."""
    cx, sx = math.cos(rx), math.sin(rx)
    cy, sy = math.cos(ry), math.sin(ry)
    cz, sz = math.cos(rz), math.sin(rz)
    R[0, 0] = cy * cz
    R[0, 1] = -cy * sz
    R[0, 2] = sy
    R[1, 0] = sx * sy * cz + cx * sz
    R[1, 1] = -sx * sy * sz + cx * cz
    R[1, 2] = -sx * cy
    R[2, 0] = -cx * sy * cz + sx * sz
    R[2, 1] = cx * sy * sz + sx * cz
    R[2, 2] = cx * cy


@njit_folded
def rotate_attachments(R, B, Rb):
    """Rb[i] = R @ B[i] for every attachment."""
    for i in range(B.shape[0]):
        for r in range(3):
            Rb[i, r] = R[r, 0] * B[i, 0] + R[r, 1] * B[i, 1] + R[r, 2] * B[i, 2]


@njit_folded
def cable_vector(A, Rb, i, px, py, pz):
    """(lx, ly, lz, L): cable i's vector l_i = a_i - (p + R b_i) [m] and its length |l_i| [m] at the
    effector position p = (px, py, pz) [m], from the outlets ``A`` (m, 3) and the rotated
    attachments ``Rb`` (m, 3) [m]."""
    lx = A[i, 0] - px - Rb[i, 0]
    ly = A[i, 1] - py - Rb[i, 1]
    lz = A[i, 2] - pz - Rb[i, 2]
    return lx, ly, lz, math.sqrt(lx * lx + ly * ly + lz * lz)


@njit_folded
def structure_matrix(px, py, pz, Rb, A, rows, W, L):
    """Fill the structure matrix ``W`` (n, m) and lengths ``L`` (m) at one pose.

    Column i is [u_i ; (R b_i) x u_i] restricted to ``rows`` (spec-format.md,
    paper eq. 9).  Returns False when a cable has zero length (its direction
    is undefined); that column of ``W`` is then zero.
    """
    m = A.shape[0]
    n = rows.shape[0]
    ok = True
    for i in range(m):
        lx, ly, lz, li = cable_vector(A, Rb, i, px, py, pz)
        L[i] = li
        if li <= 1e-12:
            ok = False
            for k in range(n):
                W[k, i] = 0.0
            continue
        fill_column(W, i, rows, lx / li, ly / li, lz / li, Rb[i, 0], Rb[i, 1], Rb[i, 2])
    return ok


@njit_folded
def fill_column(W, i, rows, ux, uy, uz, bx, by, bz):
    """Column i of the structure matrix: [u ; (R b) x u] restricted to ``rows``."""
    for k in range(rows.shape[0]):
        r = rows[k]
        if r == 0:
            W[k, i] = ux
        elif r == 1:
            W[k, i] = uy
        elif r == 2:
            W[k, i] = uz
        elif r == 3:
            W[k, i] = by * uz - bz * uy
        elif r == 4:
            W[k, i] = bz * ux - bx * uz
        else:
            W[k, i] = bx * uy - by * ux


@njit_folded
def pulley_exit(A, i, k, eref, r, bx, by, bz, C):
    """Swivel pulley of cable i: tangent point into ``C[i]``; returns (total, free) length [m].

    ``A`` (m, 3) swivel points, ``k`` (m, 3) unit swivel axes (from the winch
    into the pulley), ``eref`` (m, 3) unit reference perpendiculars (used when
    the attachment B is on the axis), ``r`` the radius [m].  The cable wraps
    beta = pi - theta_C with theta_C = atan2(z, x) + arccos(r / D) in the
    pulley plane (cdpr_design/pulley.py; Pott 2018, pulley kinematics);
    total length r beta + |B - C|.  Returns (NaN, NaN) when B is inside the
    pulley circle.
    """
    ax, ay, az = A[i, 0], A[i, 1], A[i, 2]
    dx, dy, dz = bx - ax, by - ay, bz - az
    kx, ky, kz = k[i, 0], k[i, 1], k[i, 2]
    za = dx * kx + dy * ky + dz * kz
    rx, ry, rz = dx - za * kx, dy - za * ky, dz - za * kz
    s = math.sqrt(rx * rx + ry * ry + rz * rz)
    if r <= 0.0:
        C[i, 0], C[i, 1], C[i, 2] = ax, ay, az
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        return d, d
    if s <= 1e-12:
        ex, ey, ez = eref[i, 0], eref[i, 1], eref[i, 2]
    else:
        ex, ey, ez = rx / s, ry / s, rz / s
    x = s - r
    D = math.sqrt(x * x + za * za)
    if D < r * (1.0 - 1e-12):
        C[i, 0], C[i, 1], C[i, 2] = ax, ay, az
        return np.nan, np.nan
    theta = math.atan2(za, x) + math.acos(min(1.0, r / D))
    beta = math.pi - theta
    if beta < 0.0:
        # the attachment lies ahead along +k: the cable does not touch the pulley
        C[i, 0], C[i, 1], C[i, 2] = ax, ay, az
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        return d, d
    c, sn = math.cos(theta), math.sin(theta)
    cx = ax + r * ex + r * (c * ex + sn * kx)
    cy = ay + r * ey + r * (c * ey + sn * ky)
    cz = az + r * ez + r * (c * ez + sn * kz)
    C[i, 0], C[i, 1], C[i, 2] = cx, cy, cz
    fx, fy, fz = bx - cx, by - cy, bz - cz
    free = math.sqrt(fx * fx + fy * fy + fz * fz)
    return r * beta + free, free


@njit_folded
def structure_matrix_pulley(px, py, pz, Rb, A, K, Eref, rad, rows, W, L, C):
    """:func:`structure_matrix` with swivel-pulley outlets.

    Fills ``W`` (n, m), total lengths ``L`` (m) [m] (arc + free segment) and
    the true outlet points ``C`` (m, 3) [m] (pulley tangent points; a_i where
    ``rad[i]`` = 0).  Column i is [u_i ; (R b_i) x u_i], u_i the unit vector
    from the attachment to C_i.  Returns False when a free segment has zero
    length or an attachment is inside a pulley circle (that column is zero).
    """
    m = A.shape[0]
    n = rows.shape[0]
    ok = True
    for i in range(m):
        bx = px + Rb[i, 0]
        by = py + Rb[i, 1]
        bz = pz + Rb[i, 2]
        li, free = pulley_exit(A, i, K, Eref, rad[i], bx, by, bz, C)
        L[i] = li
        if not (free > 1e-12):
            ok = False
            for kk in range(n):
                W[kk, i] = 0.0
            continue
        fill_column(W, i, rows, (C[i, 0] - bx) / free, (C[i, 1] - by) / free, (C[i, 2] - bz) / free,
                    Rb[i, 0], Rb[i, 1], Rb[i, 2])
    return ok
