"""Interference of cables, effector and frame (the paper's third workspace limit).

The seed paper lists the workspace limits of a CDPR as controllability,
tensions between limits and *cable collision avoidance* (Rivera et al., sec. 2,
after Pott 2018, ch. 6 "workspace", and Perreault, Cardou, Gosselin, Otis:
"Geometric determination of the interference-free constant-orientation
workspace of parallel cable-driven mechanisms", ASME J. Mech. Robotics 2(3), 2010).
This module checks one pose; the grid sweeps use the same kernel
(:func:`cdpr_design.kernels.interference_pose`).

What counts as a collision
--------------------------
- **cable - cable**: the free segments (attachment to true outlet point:
  the swivel-pulley tangent point, or a_i) are closer than the sum of the
  cable radii (``cable.diameter`` / 2; touching counts).  Two cables that share
  an attachment or outlet point meet there by design; they collide only when
  one's far end lies within that distance of the other (they run together).
- **cable - effector**: a free segment passes through the effector box
  (``effector.size``, centred on the platform origin) other than at its own
  attachment: the attachment is moved to the nearest face of the box when it
  lies inside it, and the cable collides when it then crosses the box's
  interior.  Grazing a face or an edge is not a collision.  The box is the
  effector's bounding box: a real platform that is a lighter frame may let
  cables through where the box does not.
- **effector - frame**: a corner of the effector box lies outside the frame box.
- **cable - frame**: an attachment point lies outside the frame box (the free
  cable leaves the frame).

Planar designs live in the z = 0 plane, but crossed cables run in offset
planes on a real machine.  A planar cable's ``plane_offset`` [m] puts its
free segment, outlet and attachment point in the plane z = plane_offset for
this check only: two cables in planes further apart than their radii' sum
never meet, and cables in one plane are checked as before.  The statics do not
change (a cable's force stays parallel to the motion plane; the out-of-plane
moments this makes are the planar guides' to take, as in every planar model).

Sagging cables (:func:`check_sagging_pose`) are checked along their catenaries, each taken as
a polyline within a stated distance of the curve (:mod:`cdpr_design.kernels.sag_clearance`):
the same checks, and a cable whose catenary sags below the frame box leaves it.

Pairs are named as ``cli.md`` says: two cable names, a cable name and
``effector`` or ``frame``, and ``("effector", "frame")``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design import kernels as K
from cdpr_design.statics import kinematics as kin
from cdpr_design.model.design import Design
from cdpr_design.statics.hardware import HardwareArrays, hardware_arrays, in_cable_planes

HIT_NAMES = {K.HIT_CABLE_CABLE: "cable-cable", K.HIT_CABLE_EFFECTOR: "cable-effector",
             K.HIT_EFFECTOR_FRAME: "effector-frame", K.HIT_CABLE_FRAME: "cable-frame"}


@dataclass(frozen=True)
class Interference:
    """Interference at one pose.

    Attributes
    ----------
    pairs : list of (str, str)
        Colliding pairs (cli.md names), cables in spec order first.
    mask : int
        Bits of :data:`HIT_NAMES`; 0 when collision free.
    cable_distances : (m, m) array
        Distance between free segments [m] (shared-endpoint rule applied; 0 on the diagonal).
    effector_chords : (m,) array
        Length of each free segment inside the effector box, own attachment excepted [m].
    curve_bounds : (m,) array or None
        Sagging cables: the largest distance between each cable's polyline and its catenary [m]
        (a pair's distance is within the sum of its two bounds of the curves'); None for straight
        cables (exact).
    """

    pairs: list
    mask: int
    cable_distances: np.ndarray
    effector_chords: np.ndarray
    curve_bounds: np.ndarray | None = None

    @property
    def collision_free(self) -> bool:
        return self.mask == 0

    @property
    def known(self) -> bool:
        """False where the sagging cables' shapes did not converge: nothing was checked."""
        return not self.mask & K.HIT_UNKNOWN

    @property
    def kinds(self) -> list[str]:
        return [name for bit, name in HIT_NAMES.items() if self.mask & bit]


def check_pose(design: Design, pose) -> Interference:
    """Cable-cable, cable-effector, effector-frame and cable-frame interference at one pose.

    ``pose`` in the motion's coordinates.  Swivel pulleys are honoured: the
    free segments end at the pulleys' tangent points.
    """
    full = design.full_pose(pose)
    g = kin.cable_geometry(design, pose)
    return _check(design, full[:3], kin.rotation_matrix(*full[3:]), g.anchors, g.exits)


def check_at(design: Design, position, R) -> Interference:
    """:func:`check_pose` at the platform origin ``position`` (3,) [m] and rotation ``R`` (3, 3),
    whatever the motion commands (a hanging effector's orientation); point outlets."""
    p = np.asarray(position, float).reshape(3)
    R = np.asarray(R, float)
    return _check(design, p, R, p + design.attachments @ R.T, design.outlets)


def interference_masks(design: Design, P, R) -> np.ndarray:
    """The interference bits (k,) uint8 (:data:`HIT_NAMES`; 0: collision free) at platform origins
    ``P`` (k, 3) [m] each with its own rotation ``R`` (k, 3, 3) (a hanging effector's), point
    outlets; 0 where the rotation is NaN (no pose).  The kernel of :func:`check_pose`, one call a pose."""
    hw = hardware_arrays(design)
    S1 = np.ascontiguousarray(in_cable_planes(design.outlets, hw.zoff))
    Bp = np.ascontiguousarray(in_cable_planes(design.attachments, hw.zoff))
    from cdpr_design.kernels import interference as KI

    scr = KI.clearance_scratch(design.m)
    cl = KI.Clearance(Bp, hw.half, hw.rho, hw.frame_lower, hw.frame_upper, hw.dim, hw.tol, False)
    out = np.zeros(len(P), np.uint8)
    for k in np.flatnonzero(np.isfinite(np.asarray(R)).all(axis=(1, 2))):
        Rk = np.ascontiguousarray(R[k])
        S0 = np.ascontiguousarray(in_cable_planes(P[k] + design.attachments @ Rk.T, hw.zoff))
        out[k] = K.interference_pose(S0, S1, Rk, float(P[k, 0]), float(P[k, 1]), float(P[k, 2]), cl, scr)
    return out


def _check(design: Design, p, R, anchors, exits) -> Interference:
    from cdpr_design.kernels import interference as KI

    hw = hardware_arrays(design)
    full = np.concatenate([p, np.zeros(3)])
    S0 = np.ascontiguousarray(in_cable_planes(anchors, hw.zoff))
    S1 = np.ascontiguousarray(in_cable_planes(exits, hw.zoff))
    Bp = np.ascontiguousarray(in_cable_planes(design.attachments, hw.zoff))
    m = design.m
    scr = KI.clearance_scratch(m)
    hits, s0, s1 = scr.hits, scr.s0, scr.s1
    cl = KI.Clearance(Bp, hw.half, hw.rho, hw.frame_lower, hw.frame_upper, hw.dim, hw.tol, True)
    mask = int(K.interference_pose(S0, S1, np.ascontiguousarray(R), full[0], full[1], full[2], cl, scr))
    dist = np.zeros((m, m))
    for i in range(m):
        for j in range(i + 1, m):
            dist[i, j] = dist[j, i] = K.cable_cable_dist(S0, S1, i, j, hw.tol, hw.dim)
    chords = np.zeros(m)
    for i in range(m):
        cpi = R.T @ (S1[i] - full[:3])
        chords[i] = K.cable_effector_chord(Bp, i, np.ascontiguousarray(cpi), hw.half, hw.dim,
                                           hw.tol, s0, s1)
    return Interference(_pairs(design, hits), mask, dist, chords)


def _pairs(design: Design, hits: np.ndarray) -> list[tuple[str, str]]:
    """The colliding pairs flagged in ``hits`` (m + 2, m + 2) (index m the effector, m + 1 the
    frame), named as cli.md says, cables in spec order first."""
    m = design.m
    names = design.cable_names + ["effector", "frame"]
    pairs = []
    for i in range(m):
        for j in range(i + 1, m):
            if hits[i, j]:
                pairs.append((names[i], names[j]))
    for i in range(m):
        if hits[i, m]:
            pairs.append((names[i], "effector"))
    for i in range(m):
        if hits[i, m + 1]:
            pairs.append((names[i], "frame"))
    if hits[m, m + 1]:
        pairs.append(("effector", "frame"))
    return pairs


def collisions(design: Design, pose) -> list[tuple[str, str]]:
    """The colliding pairs at a pose (cli.md: two cable names, or a cable and ``effector``/``frame``)."""
    return check_pose(design, pose).pairs


def sagging_clearance(robot, full: bool):
    """The sagging interference kernels' :data:`~cdpr_design.kernels.sag_clearance.SagClearance`
    of ``robot`` (a resolved :class:`~cdpr_design.statics.robot.Robot`): its effector box, cable
    radii, frame box and cable planes (:func:`hardware_arrays`), the polylines' bound
    :data:`~cdpr_design.kernels.sag_clearance.CURVE_TOL`; ``full``: every colliding pair flagged."""
    from cdpr_design.kernels import interference as KI
    from cdpr_design.kernels import sag_clearance as KC

    hw = hardware_arrays(robot.design)
    c = np.ascontiguousarray
    Bp = c(in_cable_planes(robot.attachments, hw.zoff))
    cl = KI.Clearance(Bp, c(hw.half), c(hw.rho), c(hw.frame_lower), c(hw.frame_upper), int(hw.dim), float(hw.tol),
                      bool(full))
    return KC.SagClearance(cl, c(hw.zoff, dtype=float), float(KC.CURVE_TOL), int(KC.MAX_SEGMENTS))


def check_sagging_pose(robot, full_pose) -> Interference:
    """:func:`check_pose` for ``robot``'s sagging cables (a resolved
    :class:`~cdpr_design.statics.robot.Robot` whose cables sag under its kind) at the full pose
    [x, y, z, rx, ry, rz] [m, rad]: the pose's sagging statics as the sweep's
    (:func:`cdpr_design.kernels.sag_clearance.sag_rows_at`, the robot's kind and wrenches), then
    the checks along the converged catenaries (:func:`cdpr_design.kernels.sag_clearance.pose_clearance`):
    ``cable_distances`` between the cables' polylines, each within the sum of the two cables'
    ``curve_bounds`` of the curves'.  Where the shapes did not converge nothing is checked: the
    mask is ``HIT_UNKNOWN`` (:attr:`Interference.known` False), no pairs, NaN distances."""
    from cdpr_design.kernels import sag_clearance as KC
    from cdpr_design.statics.cables import sag_robot
    from cdpr_design.statics.wrenches import wrench_vertices

    design, m = robot.design, robot.m
    full = np.asarray(full_pose, float)
    R = np.ascontiguousarray(kin.rotation_matrix(*full[3:]))
    Rb = np.ascontiguousarray(robot.attachments @ R.T)
    srob = sag_robot(robot, wrench_vertices(design, robot.kind, full[3:]), robot.kcode)
    scl = sagging_clearance(robot, True)
    rows = KC.SagRows(np.zeros(1, np.uint8), np.zeros(1), *(np.zeros((1, m)) for _ in range(5)),
                      np.zeros(1, np.int8), np.zeros(1, np.uint8), np.zeros((1, m, 3)))
    KC.sag_rows_at(np.ascontiguousarray(full[None, :3]), Rb, R, srob, scl, rows)
    nan = np.full(m, np.nan)
    if int(rows.mask[0]) & K.HIT_UNKNOWN:
        return Interference([], int(rows.mask[0]), np.full((m, m), np.nan), nan.copy(), nan.copy())
    return check_sagging_at(robot, full[:3], R, rows.shapes[0])


def check_sagging_at(robot, position, R, shapes) -> Interference:
    """:func:`check_sagging_pose` for given catenaries: platform origin ``position`` (3,) [m],
    rotation ``R`` (3, 3) (a hanging effector's), each cable's ``shapes`` (m, 3) H, VB [N] and
    unstretched length L0 [m] (:func:`sagging_masks`)."""
    from cdpr_design.kernels import sag_clearance as KC
    from cdpr_design.statics.cables import sag_cables

    m = robot.m
    p = np.asarray(position, float).reshape(3)
    R = np.ascontiguousarray(R, dtype=float)
    Rb = np.ascontiguousarray(robot.attachments @ R.T)
    out = KC.PoseClearance(np.zeros((m, m)), np.zeros(m), np.zeros(m), np.zeros((m + 2, m + 2), np.uint8))
    mask = int(KC.pose_clearance(p[0], p[1], p[2], R, Rb, np.ascontiguousarray(robot.outlet_points),
                                 np.ascontiguousarray(shapes, dtype=float),
                                 sag_cables(robot.cable, robot.rows, robot.tension_min, robot.tension_max),
                                 sagging_clearance(robot, True), out))
    return Interference(_pairs(robot.design, out.hits), mask, out.dist, out.chords, out.bound)


def sagging_masks(robot, P, R, shapes) -> np.ndarray:
    """Interference bits (k,) uint8 of ``robot``'s sagging cables at platform origins ``P`` (k, 3)
    [m] each with its rotation ``R`` (k, 3, 3), each cable's catenary given by ``shapes`` (k, m, 3):
    H, VB [N] and L0 [m] (L0 NaN: a weightless cable, its chord), checked along the curves
    (:func:`cdpr_design.kernels.sag_clearance.samples_interference`); ``HIT_UNKNOWN`` where a heavy
    cable has no shape."""
    from cdpr_design.kernels import sag_clearance as KC
    from cdpr_design.statics.cables import sag_cables

    c = np.ascontiguousarray
    R = c(R, dtype=float)
    Rb = c(np.einsum("kij,mj->kmi", R, robot.attachments))
    mask = np.zeros(len(P), dtype=np.uint8)
    cab = sag_cables(robot.cable, robot.rows, robot.tension_min, robot.tension_max)
    KC.samples_interference(c(P, dtype=float), R, Rb, c(robot.outlet_points), c(shapes, dtype=float), cab,
                            sagging_clearance(robot, False), mask)
    return mask


def path_interference(robot, poses, unstretched=None) -> np.ndarray:
    """Interference masks (k,) uint8 of ``robot`` (resolved for ``motion``) at k poses of a path
    (``poses`` (k, ncoords), the motion's coordinates [m, rad]): the bits of :func:`check_pose`
    (0: collision free).  Straight cables: :func:`check_pose` at each pose (swivel pulleys and
    cable planes honoured).  Sagging cables: the catenary of each cable's unstretched length
    ``unstretched`` (k, m) [m] (the path's set-points) at each pose
    (:func:`cdpr_design.kernels.catenary_inv.catenary_inverse_batch`), checked along the curves
    (:func:`cdpr_design.kernels.sag_clearance.samples_interference`); ``HIT_UNKNOWN`` where a
    heavy cable has no set-point or no catenary there (not checked)."""
    design = robot.design
    poses = np.atleast_2d(np.asarray(poses, float))
    k, m = poses.shape[0], design.m
    if robot.cables.straight:
        return np.array([check_pose(design, p).mask for p in poses], dtype=np.uint8)
    from cdpr_design.kernels.catenary_inv import CAT_CONVERGED, catenary_inverse_batch

    full = np.array([design.full_pose(p) for p in poses])
    R = np.ascontiguousarray(np.array([kin.rotation_matrix(*f[3:]) for f in full]))
    Rb = np.ascontiguousarray(np.einsum("kij,mj->kmi", R, robot.attachments))
    B = full[:, None, :3] + Rb
    d = robot.outlet_points[None] - B
    up = robot.cable.up
    Z = d @ up
    X = np.linalg.norm(d - Z[..., None] * up, axis=2)
    L0 = np.asarray(unstretched, float).reshape(k, m)
    w = np.broadcast_to(robot.cable.w, (k, m))
    EA = np.broadcast_to(robot.cable.EA, (k, m))
    heavy = (w > 0) & np.isfinite(L0)
    c = np.ascontiguousarray
    H, VB, status, _ = catenary_inverse_batch(c(X[heavy]), c(Z[heavy]), c(L0[heavy]), c(w[heavy]), c(EA[heavy]),
                                              np.full(heavy.sum(), np.nan), np.full(heavy.sum(), np.nan), 1e-13, 100)
    shapes = np.full((k, m, 3), np.nan)
    ok = status == CAT_CONVERGED
    idx = np.argwhere(heavy)[ok]
    shapes[idx[:, 0], idx[:, 1]] = np.column_stack([H[ok], VB[ok], L0[heavy][ok]])
    return sagging_masks(robot, full[:, :3], R, shapes)
