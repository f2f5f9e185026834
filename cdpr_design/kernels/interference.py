"""Interference kernels: cable-cable, cable-effector, effector-frame and cable-frame contacts.

Conventions in :mod:`cdpr_design.statics.interference`.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import jitable, njit, njit_folded
from cdpr_design.kernels.codes import HIT_CABLE_CABLE, HIT_CABLE_EFFECTOR, HIT_CABLE_FRAME, HIT_EFFECTOR_FRAME


@njit_folded
def _clamp01(v):
    return 0.0 if v < 0.0 else (1.0 if v > 1.0 else v)


@njit
def seg_seg_dist2(p0x, p0y, p0z, p1x, p1y, p1z, q0x, q0y, q0z, q1x, q1y, q1z):
    """Squared minimum distance [m^2] between segments [p0, p1] and [q0, q1].

    Closest points of two segments (Ericson, "Real-Time Collision Detection",
    2005, sec. 5.1.9): the unconstrained line-line parameters, clamped to
    [0, 1] one after the other; degenerate (point) segments handled.
    """
    d1x, d1y, d1z = p1x - p0x, p1y - p0y, p1z - p0z
    d2x, d2y, d2z = q1x - q0x, q1y - q0y, q1z - q0z
    rx, ry, rz = p0x - q0x, p0y - q0y, p0z - q0z
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    eps = 1e-300
    if a <= eps and e <= eps:
        return rx * rx + ry * ry + rz * rz
    if a <= eps:
        s = 0.0
        t = _clamp01(f / e)
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        if e <= eps:
            t = 0.0
            s = _clamp01(-c / a)
        else:
            b = d1x * d2x + d1y * d2y + d1z * d2z
            denom = a * e - b * b
            s = _clamp01((b * f - c * e) / denom) if denom > 1e-14 * a * e else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = _clamp01(-c / a)
            elif t > 1.0:
                t = 1.0
                s = _clamp01((b - c) / a)
    dx = rx + d1x * s - d2x * t
    dy = ry + d1y * s - d2y * t
    dz = rz + d1z * s - d2z * t
    return dx * dx + dy * dy + dz * dz


@njit_folded
def _pt_seg_dist2(x, y, z, ax, ay, az, bx, by, bz):
    return seg_seg_dist2(x, y, z, x, y, z, ax, ay, az, bx, by, bz)


@njit_folded
def cable_cable_dist(S0, S1, i, j, tol, dim):
    """Distance [m] between the free segments of cables i and j (S0 attachments, S1 exits).

    Cables that share an endpoint (attachment or outlet within ``tol``) touch
    there by construction: for them the distance is that of the far
    endpoints to the other segment (zero only when they run along each other).
    ``dim`` 2 (a planar design, its cables in planes z = their offsets): an
    endpoint is shared when x and y are, whatever the planes (two cables on
    one pin at two heights).
    """
    sa = (abs(S0[i, 0] - S0[j, 0]) <= tol and abs(S0[i, 1] - S0[j, 1]) <= tol
          and (dim == 2 or abs(S0[i, 2] - S0[j, 2]) <= tol))
    sb = (abs(S1[i, 0] - S1[j, 0]) <= tol and abs(S1[i, 1] - S1[j, 1]) <= tol
          and (dim == 2 or abs(S1[i, 2] - S1[j, 2]) <= tol))
    if sa or sb:
        if sa and sb:
            return 0.0
        F = S1 if sa else S0  # the far (non-shared) ends
        d1 = _pt_seg_dist2(F[i, 0], F[i, 1], F[i, 2], S0[j, 0], S0[j, 1], S0[j, 2],
                           S1[j, 0], S1[j, 1], S1[j, 2])
        d2 = _pt_seg_dist2(F[j, 0], F[j, 1], F[j, 2], S0[i, 0], S0[i, 1], S0[i, 2],
                           S1[i, 0], S1[i, 1], S1[i, 2])
        return math.sqrt(min(d1, d2))
    return math.sqrt(seg_seg_dist2(S0[i, 0], S0[i, 1], S0[i, 2], S1[i, 0], S1[i, 1], S1[i, 2],
                                   S0[j, 0], S0[j, 1], S0[j, 2], S1[j, 0], S1[j, 1], S1[j, 2]))


@njit_folded
def segment_box_chord(s0, s1, half, dim, shrink):
    """Length [m] of the part of segment [s0, s1] inside the open box |x_k| < half_k - shrink.

    Slab clipping (Kay & Kajiya 1986) over the first ``dim`` axes; the box
    is centred at the origin (platform coordinates).  0 when they do not meet.
    """
    t0 = 0.0
    t1 = 1.0
    seg2 = 0.0
    for ax in range(dim):
        h = half[ax] - shrink
        if h <= 0.0:
            return 0.0
        a = s0[ax]
        d = s1[ax] - a
        seg2 += d * d
        if abs(d) <= 1e-300:
            if a <= -h or a >= h:
                return 0.0
            continue
        ta = (-h - a) / d
        tb = (h - a) / d
        if ta > tb:
            ta, tb = tb, ta
        if ta > t0:
            t0 = ta
        if tb < t1:
            t1 = tb
        if t0 >= t1:
            return 0.0
    for ax in range(dim, 3):
        d = s1[ax] - s0[ax]
        seg2 += d * d
    return (t1 - t0) * math.sqrt(seg2)


@njit_folded
def effector_frame_hit(R, px, py, pz, cl, hits, m):
    """HIT_EFFECTOR_FRAME where a corner of the effector box (rotation ``R``, origin (px, py, pz)
    [m]; ``cl`` a :data:`Clearance`) is outside the frame box, else 0; with ``cl.full`` the pair
    (effector m, frame m + 1) is set in ``hits``."""
    Bp, half, rho, flo, fhi, dim, tol, full = cl
    if not effector_outside(R, px, py, pz, half, flo, fhi, dim, tol):
        return 0
    if full:
        hits[m, m + 1] = 1
        hits[m + 1, m] = 1
    return HIT_EFFECTOR_FRAME


@njit_folded
def leaving_point(Bp, i, half, dim, tol, s0):
    """Write into ``s0`` (3,) [m] where cable i leaves the effector box (half sizes ``half``), in
    platform coordinates: its attachment ``Bp[i]``, or, for an attachment inside the box (or on its
    surface within ``tol``), the nearest point of the nearest face."""
    inside = True
    best = np.inf
    bk = 0
    for ax in range(dim):
        dep = half[ax] - abs(Bp[i, ax])
        if dep < -tol:
            inside = False
        if dep < best:
            best = dep
            bk = ax
    for ax in range(3):
        s0[ax] = Bp[i, ax]
    if inside:
        s0[bk] = half[bk] if Bp[i, bk] >= 0.0 else -half[bk]


@njit_folded
def cable_effector_chord(Bp, i, cp, half, dim, tol, s0, s1):
    """Length [m] of cable i's free segment inside the effector box, its own attachment excepted.

    ``Bp`` (m, 3) attachments in platform coordinates, ``cp`` (3,) the outlet
    point in platform coordinates.  An attachment inside the box (or on its
    surface within ``tol``) is first moved to the nearest face (:func:`leaving_point`): the cable
    leaves from the surface there, and collides when it then runs through
    the box's interior (shrunk by ``tol``).  ``s0``, ``s1`` are scratch (3,).
    """
    leaving_point(Bp, i, half, dim, tol, s0)
    for ax in range(3):
        s1[ax] = cp[ax]
    return segment_box_chord(s0, s1, half, dim, tol)



@njit_folded
def point_outside(x, y, z, flo, fhi, dim, tol):
    """Whether the point (x, y, z) [m] lies outside the frame box [flo, fhi] by more than ``tol``
    (on the first ``dim`` axes: a planar design's frame is checked in x and y only)."""
    out = x < flo[0] - tol or x > fhi[0] + tol or y < flo[1] - tol or y > fhi[1] + tol
    if dim == 3:
        out = out or z < flo[2] - tol or z > fhi[2] + tol
    return out


@njit_folded
def effector_outside(R, px, py, pz, half, flo, fhi, dim, tol):
    """Whether a corner of the effector box (half extents ``half`` (3,) [m], rotation ``R``,
    origin (px, py, pz) [m]) lies outside the frame box [flo, fhi] (:func:`point_outside`)."""
    ncorner = 4 if dim == 2 else 8
    for c in range(ncorner):
        sx = half[0] if (c & 1) else -half[0]
        sy = half[1] if (c & 2) else -half[1]
        sz = half[2] if (c & 4) else -half[2]
        if dim == 2:
            sz = 0.0
        vx = px + R[0, 0] * sx + R[0, 1] * sy + R[0, 2] * sz
        vy = py + R[1, 0] * sx + R[1, 1] * sy + R[1, 2] * sz
        vz = pz + R[2, 0] * sx + R[2, 1] * sy + R[2, 2] * sz
        if point_outside(vx, vy, vz, flo, fhi, dim, tol):
            return True
    return False


#: What the interference checks need of a robot besides its pose: ``Bp`` (m, 3) the attachments
#: in platform coordinates [m], ``half`` (3,) the half extents of the effector box [m] (centred on
#: the platform origin), ``rho`` (m,) the cable radii (diameter / 2) [m], ``flo``, ``fhi`` (3,)
#: the frame box [m], ``dim`` 2 (planar: only x, y are checked) or 3, ``tol`` the geometric
#: tolerance [m], ``full``: every colliding pair (else stop at the first collision found).
Clearance = namedtuple("Clearance", "Bp half rho flo fhi dim tol full")
#: Work arrays of :func:`interference_pose`: ``hits`` (m + 2, m + 2) uint8 (the colliding pairs,
#: index m = effector, m + 1 = frame), ``s0``, ``s1``, ``cp`` (3,).
ClearanceScratch = namedtuple("ClearanceScratch", "hits s0 s1 cp")


@jitable
def clearance_scratch(m):
    """A :data:`ClearanceScratch` for ``m`` cables, ``hits`` zero."""
    return ClearanceScratch(np.zeros((m + 2, m + 2), dtype=np.uint8), np.empty(3), np.empty(3), np.empty(3))


@njit
def interference_pose(S0, S1, R, px, py, pz, cl, scr):
    """Interference at one pose; returns a bit mask (0: collision free).

    Parameters
    ----------
    S0 : (m, 3) attachment points p + R b_i in the frame [m].
    S1 : (m, 3) true outlet points (pulley tangent points or a_i) [m].
    R : (3, 3) platform rotation; (px, py, pz) platform origin [m].
    cl : :data:`Clearance`, the effector box, cable radii and frame box.
    scr : :data:`ClearanceScratch`; when ``cl.full``, ``scr.hits`` is set to 1 for each
        colliding pair (untouched otherwise).

    Bits: HIT_CABLE_CABLE (free segments closer than the sum of the cable
    radii, touching included), HIT_CABLE_EFFECTOR (a free segment through
    the effector box other than at its own attachment), HIT_EFFECTOR_FRAME
    (an effector box corner outside the frame box), HIT_CABLE_FRAME (an
    attachment point outside the frame box: the free cable leaves the frame).
    """
    Bp, half, rho, flo, fhi, dim, tol, full = cl
    hits, s0, s1, cp = scr
    m = S0.shape[0]
    mask = effector_frame_hit(R, px, py, pz, cl, hits, m)
    if mask and not full:
        return mask
    for i in range(m):
        # cable - frame: the attachment point (the free segment's end) outside the frame
        if point_outside(S0[i, 0], S0[i, 1], S0[i, 2], flo, fhi, dim, tol):
            mask |= HIT_CABLE_FRAME
            if not full:
                return mask
            hits[i, m + 1] = 1
            hits[m + 1, i] = 1
        # cable - effector, in platform coordinates: cp = R^T (C_i - p)
        dx, dy, dz = S1[i, 0] - px, S1[i, 1] - py, S1[i, 2] - pz
        for r in range(3):
            cp[r] = R[0, r] * dx + R[1, r] * dy + R[2, r] * dz
        if cable_effector_chord(Bp, i, cp, half, dim, tol, s0, s1) > tol:
            mask |= HIT_CABLE_EFFECTOR
            if not full:
                return mask
            hits[i, m] = 1
            hits[m, i] = 1
    for i in range(m):
        for j in range(i + 1, m):
            if cable_cable_dist(S0, S1, i, j, tol, dim) <= rho[i] + rho[j] + tol:
                mask |= HIT_CABLE_CABLE
                if not full:
                    return mask
                hits[i, j] = 1
                hits[j, i] = 1
    return mask
