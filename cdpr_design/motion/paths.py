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
"""

from __future__ import annotations

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
    D = segment_length(design, p0, p1)
    if D == 0.0:
        return None
    _needs_profile(traj)
    s, v, a = prof.sampled(prof.for_trajectory(traj, D, traj.speed, traj.acceleration, dt), dt)
    e = (p1 - p0) / D
    pose = p0[None, :] + s[:, None] * e[None, :]
    pose[-1] = p1  # exactly on the waypoint
    return pose, v[:, None] * e[None, :], a[:, None] * e[None, :]


def circle_samples(design: Design, traj: Trajectory, dt: float, start_angle: float = 0.0):
    """Samples of a circle path (all its laps) every ``dt`` [s], rest to rest, start included.

    Returns (pose, velocity, acceleration) arrays (N + 1, ncoords); the last
    pose is exactly on the start point.
    """
    _needs_profile(traj)
    r = float(traj.radius)
    c = np.asarray(traj.center, float)
    ori = fixed_orientation(design, traj)
    at = traj.acceleration / np.sqrt(2.0)
    vc = min(traj.speed, np.sqrt(traj.acceleration * r / np.sqrt(2.0)))
    D = 2 * np.pi * r * traj.laps
    s, v, a = prof.sampled(prof.for_trajectory(traj, D, vc, at, dt), dt, include_start=True)
    th = start_angle + s / r
    nc = len(design.motion.coords)
    pose = np.zeros((th.size, nc))
    vel = np.zeros_like(pose)
    acc = np.zeros_like(pose)
    cos, sin = np.cos(th), np.sin(th)
    pose[:, 0] = c[0] + r * cos
    pose[:, 1] = c[1] + r * sin
    if design.motion.dim == 3:
        pose[:, 2] = c[2]
    pose[:, design.motion.dim:] = ori
    vel[:, 0], vel[:, 1] = -v * sin, v * cos
    acc[:, 0] = -a * sin - v * v / r * cos
    acc[:, 1] = a * cos - v * v / r * sin
    pose[-1, :2] = c[:2] + r * np.array([np.cos(start_angle), np.sin(start_angle)])
    return pose, vel, acc


__all__ = ["as_pose", "circle_samples", "first_pose", "fixed_orientation", "line_samples",
           "path_waypoints", "segment_length"]
