"""Geometric paths of the spec's ``trajectories:`` and their samples along a speed profile.

Conventions
-----------
- Square paths lie in the x-y plane of the frame (for spatial designs at the
  centre's height z), start at the corner (cx - s/2, cy - s/2) and run
  counter-clockwise: +x, +y, -x, -y.  Circles start at angle 0, (cx + r, cy),
  and run counter-clockwise.
- A ``csv`` path is a polyline through the poses of its file.  The core never
  reads files: the caller passes the poses as ``csv_poses``.
- ``laps`` repeats the path (a polyline that does not end where it starts is
  closed by a straight segment between laps).
- The orientation of a rotational motion stays fixed along a path given by
  positions: the trajectory's ``orientation``, else the workspace's, else 0.
- For a circle the tangential acceleration is limited to a/sqrt(2) and the
  cruise speed to sqrt(a r / sqrt(2)), so that the total acceleration
  (tangential and centripetal) never exceeds the limit ``a``.

Poses are in the motion's coordinates [m, rad]; the samples of a straight
segment or an arc are (pose, velocity, acceleration) arrays, one row per cycle.
A segment or a whole circle is a :class:`Curve`: its poses q(s) by the position s
along it and their derivatives q'(s), q''(s), which a speed profile s(t) turns
into samples (:meth:`Curve.motion`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from cdpr_design.model.design import Design, Trajectory
from cdpr_design.motion import profile as prof
from cdpr_design.motion.profile import MAX_SAMPLES, too_many_samples


def fixed_orientation(design: Design, traj: Trajectory) -> np.ndarray:
    """The orientation [rad] held along the path (empty for a motion without rotations)."""
    rc = design.motion.rotation_coords
    if not rc:
        return np.zeros(0)
    if traj.orientation is not None:
        return np.asarray(traj.orientation, float)
    if design.workspace.orientation:
        return np.asarray(design.workspace.orientation, float)
    return np.zeros(len(rc))


def as_pose(design: Design, point, ori) -> np.ndarray:
    """A waypoint (position or full pose) as a pose in motion coordinates."""
    p = np.asarray(point, float).reshape(-1)
    nc = len(design.motion.coords)
    if p.size == nc:
        return p.copy()
    if p.size == design.motion.dim:
        return np.concatenate([p, ori])
    raise ValueError(f"expected {design.motion.dim} or {nc} numbers per waypoint, got {p.size}")


def path_waypoints(design: Design, traj: Trajectory, csv_poses=None) -> np.ndarray:
    """Corner poses of a square, polyline or csv path, (q, ncoords), laps included.

    The first row is where the path starts; ``start`` is not included (see
    :func:`cdpr_design.motion.trajectory.sample`).
    """
    ori = fixed_orientation(design, traj)
    if traj.type == "square":
        c = np.asarray(traj.center, float)
        h = traj.side / 2
        offs = np.array([[-h, -h], [h, -h], [h, h], [-h, h], [-h, -h]])
        pts = []
        for o in offs:
            q = c.copy()
            q[:2] = c[:2] + o
            pts.append(as_pose(design, q, ori))
        base = np.array(pts)
        closed = True
    elif traj.type in ("polyline", "csv"):
        src = traj.waypoints if traj.type == "polyline" else csv_poses
        if src is None:
            raise ValueError(f"trajectory {traj.name!r}: a csv path needs its poses (csv_poses)")
        src = np.atleast_2d(np.asarray(src, float))
        if src.shape[0] < 2:
            raise ValueError(f"trajectory {traj.name!r}: expected at least 2 poses, got {src.shape[0]}")
        base = np.array([as_pose(design, w, ori) for w in src])
        closed = bool(np.allclose(base[0], base[-1]))
    else:
        raise ValueError(f"trajectory {traj.name!r}: no corner list for a {traj.type} path")
    if base.shape[0] * traj.laps > MAX_SAMPLES:  # each corner takes a sample at least
        raise ValueError(too_many_samples(base.shape[0] * traj.laps))
    out = [base]
    for _lap in range(1, traj.laps):
        if not closed:
            out.append(base[:1])  # closing segment back to the start
        out.append(base[1:])
    return np.vstack(out)


def first_pose(design: Design, traj: Trajectory, corners=None) -> np.ndarray:
    """Where the path itself starts: the first corner, or (cx + r, cy) on a circle."""
    if traj.type != "circle":
        return corners[0]
    c = np.asarray(traj.center, float)
    first_pt = c.copy()
    first_pt[0] += traj.radius
    return as_pose(design, first_pt, fixed_orientation(design, traj))


def segment_length(design: Design, p0, p1) -> float:
    """Length of a straight segment [m]; [rad] for a pure rotation."""
    d = design.motion.dim
    dp = p1 - p0
    L = float(np.linalg.norm(dp[:d]))
    if L == 0.0:
        L = float(np.linalg.norm(dp[d:]))  # pure rotation: length in rad
    return L


@dataclass(frozen=True)
class Curve:
    """A geometric path by the position s along it, s in [0, ``length``]: ``length`` [m] (rad for a
    pure rotation), ``end`` the pose it ends at exactly (motion coordinates), ``at(s)`` the poses
    q(s), their first and second derivatives q'(s) and q''(s) at positions s (k,): three
    (k, ncoords) arrays [m, rad; per m; per m^2]; ``curved`` whether q'' is not zero (an arc)."""

    length: float
    end: np.ndarray
    at: Callable[[np.ndarray], tuple]
    curved: bool = False

    def motion(self, s, speed, accel):
        """(pose, velocity, acceleration) (k, ncoords) at positions ``s`` (k,) [m] run at path speed
        ``speed`` s' (k,) [m/s] and path acceleration ``accel`` s'' (k,) [m/s^2]: q(s), q' s' and
        q' s'' + q'' s'^2."""
        q, dq, ddq = self.at(np.asarray(s, float))
        v, a = np.asarray(speed, float)[:, None], np.asarray(accel, float)[:, None]
        return q, dq * v, dq * a + ddq * (v * v)


def line_curve(design: Design, p0, p1) -> Curve | None:
    """The straight segment p0 -> p1 (poses, motion coordinates) as a :class:`Curve` of its
    :func:`segment_length`, q(s) = p0 + s e; None for a segment of zero length.  The orientation
    of a rotational motion is interpolated along s with the position."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    D = segment_length(design, p0, p1)
    if D == 0.0:
        return None
    e = (p1 - p0) / D

    def at(s):
        q = p0[None, :] + s[:, None] * e[None, :]
        return q, np.broadcast_to(e, q.shape), np.zeros_like(q)

    return Curve(D, p1, at)


def circle_curve(design: Design, traj: Trajectory, start_angle: float = 0.0) -> Curve:
    """The circle path ``traj`` (all its laps, counter-clockwise from ``start_angle`` [rad]) as a
    :class:`Curve` of its arc length, ending exactly where it starts; the height of a spatial
    design and the orientation held (:func:`fixed_orientation`)."""
    r = float(traj.radius)
    c = np.asarray(traj.center, float)
    ori = fixed_orientation(design, traj)
    nc, dim = len(design.motion.coords), design.motion.dim
    start = np.zeros(nc)
    start[:2] = c[:2] + r * np.array([np.cos(start_angle), np.sin(start_angle)])
    if dim == 3:
        start[2] = c[2]
    start[dim:] = ori

    def at(s):
        th = start_angle + s / r
        cos, sin = np.cos(th), np.sin(th)
        q = np.zeros((th.size, nc))
        dq, ddq = np.zeros_like(q), np.zeros_like(q)
        q[:, 0] = c[0] + r * cos
        q[:, 1] = c[1] + r * sin
        if dim == 3:
            q[:, 2] = c[2]
        q[:, dim:] = ori
        dq[:, 0], dq[:, 1] = -sin, cos
        ddq[:, 0], ddq[:, 1] = -cos / r, -sin / r
        return q, dq, ddq

    return Curve(2 * np.pi * r * traj.laps, start, at, curved=True)


def _needs_profile(traj: Trajectory) -> None:
    """A ValueError naming ``speed`` / ``acceleration`` when the path lacks the limits its profile needs."""
    missing = [k for k in ("speed", "acceleration") if getattr(traj, k) is None]
    if missing:
        raise ValueError(f"{' and '.join(missing)}: needed to profile the path (or time it with --time-optimal)")


def line_samples(design: Design, traj: Trajectory, p0, p1, dt: float):
    """Samples of the straight segment p0 -> p1 every ``dt`` [s], rest to rest, p0 excluded.

    Returns (pose, velocity, acceleration) arrays (N, ncoords), the last pose
    exactly p1; None for a segment of zero length.
    """
    curve = line_curve(design, p0, p1)
    if curve is None:
        return None
    _needs_profile(traj)
    s, v, a = prof.sampled(prof.for_trajectory(traj, curve.length, traj.speed, traj.acceleration, dt), dt)
    pose, vel, acc = curve.motion(s, v, a)
    pose[-1] = curve.end  # exactly on the waypoint
    return pose, vel, acc


def circle_samples(design: Design, traj: Trajectory, dt: float, start_angle: float = 0.0):
    """Samples of a circle path (all its laps) every ``dt`` [s], rest to rest, start included.

    Returns (pose, velocity, acceleration) arrays (N + 1, ncoords); the last
    pose is exactly on the start point.
    """
    _needs_profile(traj)
    curve = circle_curve(design, traj, start_angle)
    at = traj.acceleration / np.sqrt(2.0)
    vc = min(traj.speed, np.sqrt(traj.acceleration * float(traj.radius) / np.sqrt(2.0)))
    s, v, a = prof.sampled(prof.for_trajectory(traj, curve.length, vc, at, dt), dt, include_start=True)
    pose, vel, acc = curve.motion(s, v, a)
    pose[-1] = curve.end
    return pose, vel, acc


__all__ = ["Curve", "as_pose", "circle_curve", "circle_samples", "first_pose", "fixed_orientation", "line_curve",
           "line_samples", "path_waypoints", "segment_length"]
