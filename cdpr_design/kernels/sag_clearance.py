"""Interference of sagging cables: each catenary as a polyline whose distance to the curve is bounded.

The straight cables' checks (:mod:`cdpr_design.kernels.interference`) take each free cable as
the segment from its attachment B to its outlet A.  A sagging cable is the elastic catenary its
pose's statics found (:mod:`cdpr_design.kernels.sagging`): this module takes it as a polyline of
N segments whose vertices lie on the curve at equal unstretched arc lengths s_k = k L0 / N (the
first at B, the last at A), and runs the same checks on the polylines.

**The bound.** Along the catenary the tangent turns at dtheta/ds = w H / T(s)^2 per unstretched
length, and a stretched element is (1 + T/EA) times longer, so its curvature is at most
kappa = w H / T_min^2, T_min the least tension along the cable (H where it dips below both ends,
else the smaller end tension).  A piece of arc of length l (stretched) and curvature at most kappa
lies within kappa l^2 / 8 of its chord when kappa l <= 1 (the circle of curvature kappa is the
extreme case; its sagitta is (1 - cos(kappa l / 2)) / kappa), and within l / 2 always (every
point of the arc is at most l / 2 along it from an end).  With l = L0 (1 + T_max / EA) / N the
polyline and the curve are within

    delta = min(kappa l^2 / 8 if kappa l <= 1, l / 2)

of each other, both ways (every point of one is within delta of the other).  N is the least
number of segments that makes delta <= :data:`CURVE_TOL` (at most :data:`MAX_SEGMENTS`; the
bound reached is returned per cable).  A distance between two polylines is therefore within
delta_i + delta_j of the distance between the curves; a weightless cable is its chord (N = 1,
delta = 0): the straight cables' answers exactly.

Checks, as for straight cables (:func:`~cdpr_design.kernels.interference.interference_pose`):

- cable - cable: the polylines closer than the sum of the cable radii (touching included);
  cables that share an attachment or an outlet meet there by design and collide when one's far
  end comes within that distance of the other cable;
- cable - effector: a polyline through the effector box other than at its own attachment;
- effector - frame: a corner of the effector box outside the frame box;
- cable - frame: the attachment outside the frame box, or the catenary's lowest point (where it
  dips below both ends) outside it: a cable that sags through the floor.

A pose whose cables have no converged shapes is not checked: its mask is :data:`HIT_UNKNOWN`.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import jitable, njit, njit_folded
from cdpr_design.kernels.catenary import catenary_ends
from cdpr_design.kernels.codes import (HIT_CABLE_CABLE, HIT_CABLE_EFFECTOR, HIT_CABLE_FRAME,
                                      HIT_UNKNOWN)
from cdpr_design.kernels.interference import (Clearance, ClearanceScratch, clearance_scratch, effector_frame_hit,
                                              leaving_point, point_outside, seg_seg_dist2,
                                              segment_box_chord)
from cdpr_design.kernels.parallel import run_blocks
from cdpr_design.kernels.pose import RowBlock
from cdpr_design.kernels.sag_shapes import CW_H, CW_L0, CW_VB
from cdpr_design.kernels.sagging import SAG_OK, redundancy, sag_buffers, sag_pose, store_row
from cdpr_design.kernels.scalar import hypot

#: The largest distance [m] allowed between a cable's polyline and its catenary (0.1 mm).
CURVE_TOL = 1e-4
#: The most segments of a cable's polyline (a cable that would need more has a larger bound).
MAX_SEGMENTS = 1024

#: What the sagging interference checks need: ``cl`` the straight checks'
#: :data:`~cdpr_design.kernels.interference.Clearance`, ``zoff`` (m,) a planar design's cable
#: planes z = zoff [m] (zeros for a spatial one), ``delta`` the polylines' target bound [m]
#: (:data:`CURVE_TOL`), ``nmax`` the most segments a polyline has (:data:`MAX_SEGMENTS`).
SagClearance = namedtuple("SagClearance", "cl zoff delta nmax")
#: The cables' polylines at one pose: ``pts`` (m, nmax + 1, 3) vertices [m] (B first), ``nseg``
#: (m,) int64 segments, ``bound`` (m,) the distance bound between polyline and curve [m], ``dip``
#: (m, 3) the catenary's lowest point [m] where it dips below both ends (NaN where it does not).
Curves = namedtuple("Curves", "pts nseg bound dip")


@jitable
def make_curves(m, nmax):
    """The :data:`Curves` of ``m`` cables of at most ``nmax`` segments."""
    return Curves(np.empty((m, nmax + 1, 3)), np.zeros(m, dtype=np.int64), np.zeros(m), np.full((m, 3), np.nan))


@njit_folded
def _segments(ls, kappa, delta, nmax):
    """(N, bound [m]): the least number of segments, at most ``nmax``, whose polyline is within
    ``delta`` [m] of an arc of stretched length ``ls`` [m] and curvature at most ``kappa`` [1/m]."""
    n = 1
    if kappa > 0.0 and ls > 0.0:
        need = ls * math.sqrt(kappa / (8.0 * delta)) if math.isfinite(kappa) else float(nmax)
        n = int(min(float(nmax), max(1.0, math.ceil(need))))
    ell = ls / n
    bound = 0.5 * ell
    if kappa * ell <= 1.0:
        bound = min(bound, kappa * ell * ell / 8.0)
    return n, bound


@njit
def cable_curve(i, B, A, H, VB, L0, w, EA, up, zoff, delta, nmax, curves):
    """Cable i's polyline into ``curves`` (:data:`Curves`): from its attachment ``B`` (3,) to its
    outlet ``A`` (3,) [m] (both in the frame, before the plane offset ``zoff`` [m] is added to z)
    in their vertical plane (``up`` (3,) the unit vector against gravity), its shape the end
    forces ``H``, ``VB`` [N] and unstretched length ``L0`` [m], its weight per length ``w``
    [N/m] and axial stiffness ``EA`` [N].  A weightless cable, or one without a shape (slack:
    L0 NaN), is its chord."""
    pts, nseg, bound, dip = curves
    for r in range(3):
        pts[i, 0, r] = B[r]
        dip[i, r] = math.nan
    pts[i, 0, 2] += zoff
    n, b = 1, 0.0
    if w > 0.0 and L0 > 0.0 and H >= 0.0:
        # the horizontal unit vector from B towards A (0 for a vertical cable), as the statics'
        lx, ly, lz = A[0] - B[0], A[1] - B[1], A[2] - B[2]
        Z = lx * up[0] + ly * up[1] + lz * up[2]
        hx, hy, hz = lx - Z * up[0], ly - Z * up[1], lz - Z * up[2]
        X = math.sqrt(hx * hx + hy * hy + hz * hz)
        ux = uy = uz = 0.0
        if X > 1e-14 * math.sqrt(lx * lx + ly * ly + lz * lz):
            ux, uy, uz = hx / X, hy / X, hz / X
        VA = VB + w * L0
        TA, TB = hypot(H, VA), hypot(H, VB)
        dips = VB < 0.0 < VA
        tmin = H if dips else min(TA, TB)
        kappa = w * H / (tmin * tmin) if tmin > 0.0 else math.inf
        n, b = _segments(L0 * (1.0 + max(TA, TB) / EA), kappa, delta, nmax)
        for k in range(1, n):
            x, z = catenary_ends(H, VB, L0 * k / n, w, EA)
            pts[i, k, 0] = B[0] + x * ux + z * up[0]
            pts[i, k, 1] = B[1] + x * uy + z * up[1]
            pts[i, k, 2] = B[2] + x * uz + z * up[2] + zoff
        if dips:
            x, z = catenary_ends(H, VB, -VB / w, w, EA)
            dip[i, 0] = B[0] + x * ux + z * up[0]
            dip[i, 1] = B[1] + x * uy + z * up[1]
            dip[i, 2] = B[2] + x * uz + z * up[2] + zoff
    for r in range(3):
        pts[i, n, r] = A[r]
    pts[i, n, 2] += zoff
    nseg[i] = n
    bound[i] = b


@njit_folded
def _box_gap2(alo0, alo1, alo2, ahi0, ahi1, ahi2, blo0, blo1, blo2, bhi0, bhi1, bhi2):
    """Squared distance [m^2] between two axis-aligned boxes (0 when they meet)."""
    g = 0.0
    d = max(blo0 - ahi0, alo0 - bhi0, 0.0)
    g += d * d
    d = max(blo1 - ahi1, alo1 - bhi1, 0.0)
    g += d * d
    d = max(blo2 - ahi2, alo2 - bhi2, 0.0)
    return g + d * d


#: Segments of a polyline bounded together by :func:`curve_distance` before their own boxes.
CHUNK = 16


@njit_folded
def _chunk_box(pts, i, k0, k1):
    """The bounding box (lo0, lo1, lo2, hi0, hi1, hi2) [m] of vertices k0..k1 of cable i."""
    lo0 = lo1 = lo2 = math.inf
    hi0 = hi1 = hi2 = -math.inf
    for k in range(k0, k1 + 1):
        lo0, hi0 = min(lo0, pts[i, k, 0]), max(hi0, pts[i, k, 0])
        lo1, hi1 = min(lo1, pts[i, k, 1]), max(hi1, pts[i, k, 1])
        lo2, hi2 = min(lo2, pts[i, k, 2]), max(hi2, pts[i, k, 2])
    return lo0, lo1, lo2, hi0, hi1, hi2


@njit
def curve_distance(pts, nseg, i, j, stop):
    """Least distance [m] between the polylines of cables i and j (:data:`Curves`' ``pts``,
    ``nseg``); it returns as soon as a distance at or below ``stop`` [m] is found (that distance:
    pass -1 for the least one).  Runs of :data:`CHUNK` segments whose bounding boxes are farther
    apart than the best distance so far are skipped, then single segments the same way, so that
    two long cables that meet only near one end cost little more than their near ends."""
    best = math.inf
    for a0 in range(0, nseg[i], CHUNK):
        a1 = min(a0 + CHUNK, nseg[i])
        A0, A1, A2, A3, A4, A5 = _chunk_box(pts, i, a0, a1)
        for b0 in range(0, nseg[j], CHUNK):
            b1 = min(b0 + CHUNK, nseg[j])
            B0, B1, B2, B3, B4, B5 = _chunk_box(pts, j, b0, b1)
            if _box_gap2(A0, A1, A2, A3, A4, A5, B0, B1, B2, B3, B4, B5) >= best:
                continue
            for a in range(a0, a1):
                p0x, p0y, p0z = pts[i, a, 0], pts[i, a, 1], pts[i, a, 2]
                p1x, p1y, p1z = pts[i, a + 1, 0], pts[i, a + 1, 1], pts[i, a + 1, 2]
                ax0, ax1 = min(p0x, p1x), max(p0x, p1x)
                ay0, ay1 = min(p0y, p1y), max(p0y, p1y)
                az0, az1 = min(p0z, p1z), max(p0z, p1z)
                if _box_gap2(ax0, ay0, az0, ax1, ay1, az1, B0, B1, B2, B3, B4, B5) >= best:
                    continue
                for b in range(b0, b1):
                    q0x, q0y, q0z = pts[j, b, 0], pts[j, b, 1], pts[j, b, 2]
                    q1x, q1y, q1z = pts[j, b + 1, 0], pts[j, b + 1, 1], pts[j, b + 1, 2]
                    if _box_gap2(ax0, ay0, az0, ax1, ay1, az1, min(q0x, q1x), min(q0y, q1y), min(q0z, q1z),
                                 max(q0x, q1x), max(q0y, q1y), max(q0z, q1z)) >= best:
                        continue
                    d2 = seg_seg_dist2(p0x, p0y, p0z, p1x, p1y, p1z, q0x, q0y, q0z, q1x, q1y, q1z)
                    if d2 < best:
                        best = d2
                        if math.sqrt(best) <= stop:
                            return math.sqrt(best)
    return math.sqrt(best)


@njit_folded
def _point_curve2(x, y, z, pts, nseg, j):
    """Squared distance [m^2] from the point (x, y, z) to cable j's polyline."""
    best = math.inf
    for b in range(nseg[j]):
        best = min(best, seg_seg_dist2(x, y, z, x, y, z, pts[j, b, 0], pts[j, b, 1], pts[j, b, 2],
                                       pts[j, b + 1, 0], pts[j, b + 1, 1], pts[j, b + 1, 2]))
    return best


@njit_folded
def _same(pts, i, ki, j, kj, tol, dim):
    """Whether vertex ki of cable i and vertex kj of cable j coincide within ``tol`` (a planar
    design's cables: in x and y, whatever their planes)."""
    return (abs(pts[i, ki, 0] - pts[j, kj, 0]) <= tol and abs(pts[i, ki, 1] - pts[j, kj, 1]) <= tol
            and (dim == 2 or abs(pts[i, ki, 2] - pts[j, kj, 2]) <= tol))


@njit
def cable_pair_distance(curves, i, j, tol, dim, stop):
    """Distance [m] between cables i and j's polylines (:data:`Curves`), with the straight checks'
    rule for cables that share an end (:func:`~cdpr_design.kernels.interference.cable_cable_dist`):
    those meet there by design, and their distance is that of each far end to the other cable.
    ``stop``: as :func:`curve_distance`."""
    pts, nseg = curves.pts, curves.nseg
    ni, nj = nseg[i], nseg[j]
    sa = _same(pts, i, 0, j, 0, tol, dim)
    sb = _same(pts, i, ni, j, nj, tol, dim)
    if sa and sb:
        return 0.0
    if sa or sb:
        fi = ni if sa else 0
        fj = nj if sa else 0
        d1 = _point_curve2(pts[i, fi, 0], pts[i, fi, 1], pts[i, fi, 2], pts, nseg, j)
        d2 = _point_curve2(pts[j, fj, 0], pts[j, fj, 1], pts[j, fj, 2], pts, nseg, i)
        return math.sqrt(min(d1, d2))
    return curve_distance(pts, nseg, i, j, stop)


@njit
def curve_effector_chord(curves, i, Bp, R, px, py, pz, half, dim, tol, s0, s1):
    """Length [m] of cable i's polyline inside the effector box (shrunk by ``tol``), its own
    attachment excepted: :func:`~cdpr_design.kernels.interference.cable_effector_chord` segment by
    segment, in platform coordinates (``Bp`` (m, 3) attachments there [m], ``R``, (px, py, pz) the
    platform's rotation and origin).  ``s0``, ``s1`` are scratch (3,)."""
    pts, nseg = curves.pts, curves.nseg
    leaving_point(Bp, i, half, dim, tol, s0)
    total = 0.0
    for k in range(nseg[i]):
        if k > 0:
            for r in range(3):
                s0[r] = s1[r]
        dx, dy, dz = pts[i, k + 1, 0] - px, pts[i, k + 1, 1] - py, pts[i, k + 1, 2] - pz
        for r in range(3):
            s1[r] = R[0, r] * dx + R[1, r] * dy + R[2, r] * dz
        total += segment_box_chord(s0, s1, half, dim, tol)
    return total


@njit
def curves_interference(curves, R, px, py, pz, scl, scr):
    """Interference of the cables' polylines ``curves`` (:data:`Curves`) at one pose: the bit mask
    of :func:`~cdpr_design.kernels.interference.interference_pose` (0: collision free), the
    colliding pairs in ``scr.hits`` when ``scl.cl.full`` (:data:`SagClearance`, ``scr`` a
    :data:`~cdpr_design.kernels.interference.ClearanceScratch`)."""
    Bp, half, rho, flo, fhi, dim, tol, full = scl.cl
    hits, s0, s1 = scr.hits, scr.s0, scr.s1
    pts, nseg, dip = curves.pts, curves.nseg, curves.dip
    m = nseg.shape[0]
    mask = effector_frame_hit(R, px, py, pz, scl.cl, hits, m)
    if mask and not full:
        return mask
    for i in range(m):
        out = point_outside(pts[i, 0, 0], pts[i, 0, 1], pts[i, 0, 2], flo, fhi, dim, tol)
        if not math.isnan(dip[i, 0]):
            out = out or point_outside(dip[i, 0], dip[i, 1], dip[i, 2], flo, fhi, dim, tol)
        if out:
            mask |= HIT_CABLE_FRAME
            if not full:
                return mask
            hits[i, m + 1] = 1
            hits[m + 1, i] = 1
        if curve_effector_chord(curves, i, Bp, R, px, py, pz, half, dim, tol, s0, s1) > tol:
            mask |= HIT_CABLE_EFFECTOR
            if not full:
                return mask
            hits[i, m] = 1
            hits[m, i] = 1
    for i in range(m):
        for j in range(i + 1, m):
            reach = rho[i] + rho[j] + tol
            if cable_pair_distance(curves, i, j, tol, dim, reach) <= reach:
                mask |= HIT_CABLE_CABLE
                if not full:
                    return mask
                hits[i, j] = 1
                hits[j, i] = 1
    return mask


@njit
def pose_curves(px, py, pz, Rb, A, shapes, cab, scl, curves, B):
    """Every cable's polyline (:func:`cable_curve`) at the effector position (px, py, pz) [m]
    with attachments rotated to ``Rb`` (m, 3) [m], outlets ``A`` (m, 3) [m], the cables' shapes
    ``shapes`` (m, 3) (H, VB [N], L0 [m] each) and the cables ``cab``
    (:data:`~cdpr_design.kernels.sag_shapes.SagCables`).  ``B`` (3,) is scratch."""
    for i in range(A.shape[0]):
        B[0], B[1], B[2] = px + Rb[i, 0], py + Rb[i, 1], pz + Rb[i, 2]
        cable_curve(i, B, A[i], shapes[i, 0], shapes[i, 1], shapes[i, 2], cab.w[i], cab.EA[i], cab.up,
                    scl.zoff[i], scl.delta, scl.nmax, curves)


#: Rows of :func:`sag_rows_at`: as :data:`~cdpr_design.kernels.sagging.GridOutputs` (``feasible``
#: (k,) uint8, ``margin`` (k,), ``tensions``, ``lengths``, ``outlet``, ``L0``, ``sag`` (k, m),
#: ``status`` (k,) int8), ``mask`` (k,) uint8 the interference bits (0 when not checked;
#: :data:`HIT_UNKNOWN` where the shapes did not converge) and ``shapes`` (k, m, 3): each cable's
#: H, VB [N] and L0 [m] (NaN without converged shapes), or (0, m, 3): not kept.
SagRows = namedtuple("SagRows", "feasible margin tensions lengths outlet L0 sag status mask shapes")


def sag_rows_at(P, Rb, R, robot, scl, out):
    """:func:`~cdpr_design.kernels.sagging.sag_pose` at positions ``P`` (k, 3) [m] at one
    orientation (rotation ``R`` (3, 3), attachments rotated to ``Rb`` (m, 3) [m]) for ``robot``
    (:data:`~cdpr_design.kernels.sagging.SagRobot`), with the interference of the converged
    cables (``scl`` a :data:`SagClearance`, or None: not checked), into ``out`` (:data:`SagRows`)."""
    redundant = redundancy(robot.cables.rows.shape[0], robot.A.shape[0])
    run_blocks(_ROWS_BLOCK, P.shape[0], P, Rb, R, robot, scl, out, redundant, grain=16)


def _rows_buffers(n, m, nv):
    """:func:`~cdpr_design.kernels.sagging.sag_buffers`, the polylines, the checks' scratch, a
    pose's shapes (m, 3) and a point (3,)."""
    return sag_buffers(n, m, nv) + (make_curves(m, MAX_SEGMENTS), clearance_scratch(m), np.empty((m, 3)),
                                    np.empty(3))


@njit
def _rows_loop(k0, k1, P, Rb, R, robot, scl, out, redundant, po, sc, curves, cscr, shp, B):
    """Rows k0..k1-1 of :func:`sag_rows_at`, with the block's buffers (:func:`_rows_buffers`)."""
    m = robot.A.shape[0]
    keep = out.shapes.shape[0] == P.shape[0]
    cw = sc.fixed.cw
    for k in range(k0, k1):
        px, py, pz = P[k, 0], P[k, 1], P[k, 2]
        st, f, mg = sag_pose(px, py, pz, Rb, robot, po, sc, redundant)
        store_row(out, k, st, f, mg, po, m)
        ok = st == SAG_OK
        for i in range(m):
            shp[i, 0] = cw[i, CW_H] if ok else math.nan
            shp[i, 1] = cw[i, CW_VB] if ok else math.nan
            shp[i, 2] = cw[i, CW_L0] if ok else math.nan
            if keep:
                for r in range(3):
                    out.shapes[k, i, r] = shp[i, r]
        if scl is None:
            out.mask[k] = 0
        elif st != SAG_OK:
            out.mask[k] = HIT_UNKNOWN
        else:
            pose_curves(px, py, pz, Rb, robot.A, shp, robot.cables, scl, curves, B)
            out.mask[k] = curves_interference(curves, R, px, py, pz, scl, cscr)


_ROWS_BLOCK = RowBlock(_rows_loop, lambda P, Rb, R, robot, *rest: (robot.cables.rows.shape[0], robot.A.shape[0],
                                                                  robot.wreq.shape[0]), buffers=_rows_buffers)

#: One pose's clearances (:func:`pose_clearance`): ``dist`` (m, m) the distance between each pair of
#: polylines [m] (0 on the diagonal), ``chords`` (m,) each polyline's length inside the effector
#: box [m], ``bound`` (m,) each polyline's distance bound [m], ``hits`` (m + 2, m + 2) uint8 the
#: colliding pairs (index m the effector, m + 1 the frame).
PoseClearance = namedtuple("PoseClearance", "dist chords bound hits")


@njit
def pose_clearance(px, py, pz, R, Rb, A, shapes, cab, scl, out):
    """Interference of sagging cables at one pose, with every pair's distance: returns the mask.

    The effector at (px, py, pz) [m] with rotation ``R`` and attachments rotated to ``Rb`` (m, 3)
    [m], outlets ``A`` (m, 3) [m], the cables' shapes ``shapes`` (m, 3) (H, VB [N], L0 [m]; the
    :data:`SagRows` of the pose), ``cab`` the cables, ``scl`` the checks (:data:`SagClearance`;
    every colliding pair is flagged whatever ``scl.cl.full``), into ``out``
    (:data:`PoseClearance`).  Each distance is within ``bound[i] + bound[j]`` of the curves'.
    """
    Bp, half, rho, flo, fhi, dim, tol, full = scl.cl
    m = A.shape[0]
    curves = make_curves(m, scl.nmax)
    pose_curves(px, py, pz, Rb, A, shapes, cab, scl, curves, np.empty(3))
    scr = ClearanceScratch(out.hits, np.empty(3), np.empty(3), np.empty(3))
    out.hits[:, :] = 0
    every = SagClearance(Clearance(Bp, half, rho, flo, fhi, dim, tol, True), scl.zoff, scl.delta, scl.nmax)
    mask = curves_interference(curves, R, px, py, pz, every, scr)
    for i in range(m):
        out.dist[i, i] = 0.0
        for j in range(i + 1, m):
            d = cable_pair_distance(curves, i, j, tol, dim, -1.0)
            out.dist[i, j] = d
            out.dist[j, i] = d
        out.chords[i] = curve_effector_chord(curves, i, Bp, R, px, py, pz, half, dim, tol, scr.s0, scr.s1)
        out.bound[i] = curves.bound[i]
    return mask


def samples_interference(P, R, Rb, A, shapes, cab, scl, mask):
    """Interference of sagging cables at k samples of a path, each with its own pose and shapes:
    ``P`` (k, 3) positions [m], ``R`` (k, 3, 3) rotations, ``Rb`` (k, m, 3) rotated attachments [m],
    ``A`` (m, 3) outlets [m], ``shapes`` (k, m, 3) each cable's H, VB [N] and L0 [m] (L0 NaN: a
    weightless cable, its chord), ``cab`` the cables
    (:data:`~cdpr_design.kernels.sag_shapes.SagCables`), ``scl`` the checks (:data:`SagClearance`),
    into ``mask`` (k,) uint8 (:func:`curves_interference`'s bits; :data:`HIT_UNKNOWN` where a heavy
    cable has no shape)."""
    run_blocks(_SAMPLES_BLOCK, P.shape[0], P, R, Rb, A, shapes, cab, scl, mask, grain=64)


@njit
def _samples_loop(k0, k1, P, R, Rb, A, shapes, cab, scl, mask, curves, cscr, B):
    """Samples k0..k1-1 of :func:`samples_interference`, with the block's polylines and scratch."""
    m = A.shape[0]
    for k in range(k0, k1):
        known = True
        for i in range(m):
            if cab.w[i] > 0.0 and not (shapes[k, i, 2] > 0.0 and shapes[k, i, 0] >= 0.0):
                known = False
        if not known:
            mask[k] = HIT_UNKNOWN
            continue
        pose_curves(P[k, 0], P[k, 1], P[k, 2], Rb[k], A, shapes[k], cab, scl, curves, B)
        mask[k] = curves_interference(curves, R[k], P[k, 0], P[k, 1], P[k, 2], scl, cscr)


_SAMPLES_BLOCK = RowBlock(_samples_loop, lambda P, R, Rb, A, *rest: (0, A.shape[0], 0),
                          buffers=lambda n, m, nv: (make_curves(m, MAX_SEGMENTS), clearance_scratch(m), np.empty(3)))
