"""Trajectory sampling: paths, speed profiles and per-sample axis set-points.

A named path of the spec's ``trajectories:`` section (square, polyline,
circle, or a table of poses) is sampled at a fixed cycle time (default 1 ms,
a PLC cycle) with a rest-to-rest speed profile on every straight segment
(trapezoidal, or jerk-limited "S-curve" when ``jerk`` is given) and one
profile over the whole arc of a circle.  Every sample carries what a winch
controller and a sizing study need: the pose and its derivatives, the cable
lengths, speeds and accelerations, the motor angles and the cable tensions
that hold the effector *with its inertia* (d'Alembert), and a feasibility flag.

Conventions
-----------
- Straight segments start and end at rest, so the path never cuts a corner
  and the effector never flies ballistic at a corner (a cable robot cannot pull
  downwards faster than gravity).  Each segment's duration is stretched to a
  whole number of cycles by uniform time scaling (speed / lambda,
  acceleration / lambda^2, jerk / lambda^3, lambda >= 1), so the limits hold
  and a sample falls *exactly* on every waypoint.
- Square paths lie in the x-y plane of the frame (for spatial designs at the
  centre's height z), start at the corner (cx - s/2, cy - s/2) and run
  counter-clockwise: +x, +y, -x, -y.  Circles start at angle 0, (cx + r, cy),
  and run counter-clockwise.
- A ``csv`` path is a polyline through the poses of its file.  The core never
  reads files: the caller passes the poses as ``csv_poses``.
- ``start`` (when it differs from the path's first point) adds a straight
  approach segment; ``laps`` repeats the path (a polyline that does not end
  where it starts is closed by a straight segment between laps).
- Motor angle: ``theta_i = (L_i - L_i(0)) / r_i * gear_ratio_i`` [rad], zero
  at the trajectory's first sample (the homed position), positive when cable is
  paid out (the cable gets longer).
- For a circle the tangential acceleration is limited to a/sqrt(2) and the
  cruise speed to sqrt(a r / sqrt(2)), so that the total acceleration
  (tangential and centripetal) never exceeds the limit ``a``.

References
----------
Rivera, Garrido, Riveiro, Silva: "Environment for the Design and Automation
of New CDPR Architectures" (the seed paper), section 4: the square test path
at 100 and 1000 mm/s; eq. (1)-(3) inverse kinematics; eq. (6)-(9) statics.
Biagiotti & Melchiorri, "Trajectory Planning for Automatic Machines and
Robots", Springer 2008, sections 3.2 (trapezoidal) and 3.4 (double-S) profiles.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cdpr_design.statics import pulley as pl
from cdpr_design.model.design import Design, Trajectory

DEFAULT_CYCLE_TIME = 1e-3
"""Default sample period [s]: one PLC cycle."""

TENSION_TOL = 1e-9
"""Tolerance [N] on the tension bounds for the feasibility flag."""


# ----------------------------------------------------------------------------
# Result
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Segment:
    """One piece of the sampled path.

    Attributes
    ----------
    index : int
        Segment number (the value of :attr:`Samples.segment` on its samples).
    kind : str
        ``line`` (a straight segment of the path), ``approach`` (from
        ``start`` to the path) or ``arc`` (a circle).
    start, end : (ncoords,) arrays
        Poses at its ends (motion coordinates).
    first, last : int
        Sample indices of its first and last samples (both on the segment).
    """

    index: int
    kind: str
    start: np.ndarray
    end: np.ndarray
    first: int
    last: int


@dataclass(frozen=True)
class Samples:
    """A sampled trajectory (k samples, m cables, motion coordinates).

    Attributes
    ----------
    name : str
        Trajectory name.
    coords : tuple of str
        Pose coordinate names (``x, y`` ... in the motion's order).
    cable_names : tuple of str
    time : (k,) array
        Sample times [s], ``j * cycle_time``.
    pose, velocity, acceleration : (k, ncoords) arrays
        Pose [m, rad] and its first and second time derivatives.
    lengths, cable_speed, cable_accel : (k, m) arrays
        Cable lengths [m], dL/dt [m/s] and d2L/dt2 [m/s^2] (analytic).
    motor_angle : (k, m) array
        Motor shaft angle [rad] (see the module notes for the sign and zero).
    tensions : (k, m) array
        Tensions [N] balancing gravity and the effector's inertia; NaN where
        the structure matrix is singular.
    feasible : (k,) bool array
        Tensions finite and within every cable's bounds.
    segment : (k,) int array
        Segment index of each sample (a corner sample belongs to the segment
        it ends).
    segments : tuple of Segment
    cycle_time : float
        [s]
    """

    name: str
    coords: tuple[str, ...]
    cable_names: tuple[str, ...]
    time: np.ndarray
    pose: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    lengths: np.ndarray
    cable_speed: np.ndarray
    cable_accel: np.ndarray
    motor_angle: np.ndarray
    tensions: np.ndarray
    feasible: np.ndarray
    segment: np.ndarray
    segments: tuple[Segment, ...] = field(default_factory=tuple)
    cycle_time: float = DEFAULT_CYCLE_TIME

    def __len__(self) -> int:
        return int(self.time.size)

    @property
    def duration(self) -> float:
        """Total duration [s]."""
        return float(self.time[-1] - self.time[0]) if self.time.size else 0.0

    @property
    def all_feasible(self) -> bool:
        return bool(np.all(self.feasible))

    def columns(self) -> dict[str, np.ndarray]:
        """The ``trajectory.csv`` columns of the CLI contract, in order."""
        out: dict[str, np.ndarray] = {"time": self.time}
        for j, c in enumerate(self.coords):
            out[c] = self.pose[:, j]
        for j, c in enumerate(self.coords):
            out[f"{c}_vel"] = self.velocity[:, j]
        for i, c in enumerate(self.cable_names):
            out[f"length_{c}"] = self.lengths[:, i]
            out[f"cable_speed_{c}"] = self.cable_speed[:, i]
            out[f"motor_angle_{c}"] = self.motor_angle[:, i]
            out[f"tension_{c}"] = self.tensions[:, i]
        out["feasible"] = self.feasible.astype(np.int64)
        # added columns (after the contract's)
        for j, c in enumerate(self.coords):
            out[f"{c}_acc"] = self.acceleration[:, j]
        for i, c in enumerate(self.cable_names):
            out[f"cable_accel_{c}"] = self.cable_accel[:, i]
        out["segment"] = self.segment.astype(np.int64)
        return out

    def summary(self) -> dict:
        """Headline figures (JSON-ready)."""
        speed = np.linalg.norm(self.velocity[:, : _pos_dim(self.coords)], axis=1)
        acc = np.linalg.norm(self.acceleration[:, : _pos_dim(self.coords)], axis=1)
        with np.errstate(invalid="ignore"):
            return {
                "name": self.name,
                "samples": int(self.time.size),
                "duration": self.duration,
                "cycle_time": self.cycle_time,
                "feasible": self.all_feasible,
                "infeasible_samples": int(np.count_nonzero(~self.feasible)),
                "max_speed": float(speed.max()) if speed.size else 0.0,
                "max_acceleration": float(acc.max()) if acc.size else 0.0,
                "max_tension": _nan_to_none(np.nanmax(self.tensions, axis=0), self.cable_names),
                "min_tension": _nan_to_none(np.nanmin(self.tensions, axis=0), self.cable_names),
                "max_cable_speed": dict(zip(self.cable_names, map(float, np.abs(self.cable_speed).max(axis=0)))),
                "segments": len(self.segments),
            }


def _nan_to_none(values, names):
    return {n: (None if not np.isfinite(v) else float(v)) for n, v in zip(names, values)}


def _pos_dim(coords) -> int:
    return sum(1 for c in coords if c in ("x", "y", "z"))


# ----------------------------------------------------------------------------
# Speed profiles (rest to rest)
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Profile:
    """A rest-to-rest motion law s(t) over distance ``distance``.

    Piecewise-constant jerk: phase p lasts ``durations[p]``, starts with
    acceleration ``a0[p]`` and has jerk ``jerk[p]`` (a trapezoid has zero
    jerk and acceleration steps).  ``scale`` >= 1 is the uniform time scaling
    applied afterwards (t' = scale * t).
    """

    distance: float
    durations: np.ndarray
    a0: np.ndarray
    jerk: np.ndarray
    scale: float = 1.0

    @property
    def raw_duration(self) -> float:
        return float(self.durations.sum())

    @property
    def duration(self) -> float:
        """Duration after time scaling [s]."""
        return self.raw_duration * self.scale

    def evaluate(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position s [m], speed [m/s] and acceleration [m/s^2] at times t [s] (scaled time)."""
        t = np.asarray(t, dtype=float) / self.scale
        d, a0, j = self.durations, self.a0, self.jerk
        # state at the start of each phase
        n = d.size
        s0 = np.zeros(n + 1)
        v0 = np.zeros(n + 1)
        for p in range(n):
            T = d[p]
            s0[p + 1] = s0[p] + v0[p] * T + a0[p] * T * T / 2 + j[p] * T ** 3 / 6
            v0[p + 1] = v0[p] + a0[p] * T + j[p] * T * T / 2
        ends = np.cumsum(d)
        starts = ends - d
        p = np.clip(np.searchsorted(ends, t, side="right"), 0, n - 1)
        tau = np.clip(t - starts[p], 0.0, None)
        s = s0[p] + v0[p] * tau + a0[p] * tau ** 2 / 2 + j[p] * tau ** 3 / 6
        v = v0[p] + a0[p] * tau + j[p] * tau ** 2 / 2
        a = a0[p] + j[p] * tau
        # exact end: the raw law reaches `distance` up to rounding; remove it
        total = s0[n]
        if total > 0:
            s = s * (self.distance / total)
        after = t >= self.raw_duration * (1 - 1e-12)  # the last cycle lands on the end despite rounding
        s = np.where(after, self.distance, s)
        v = np.where(after, 0.0, v)
        a = np.where(after, 0.0, a)
        return s, v / self.scale, a / self.scale ** 2


def trapezoid(distance: float, speed: float, acceleration: float) -> Profile:
    """Minimum-time rest-to-rest trapezoidal profile (triangular when short).

    Parameters
    ----------
    distance : float
        Path length [m] (or [rad]), >= 0.
    speed, acceleration : float
        Limits [m/s], [m/s^2], > 0.
    """
    D, v, a = float(distance), float(speed), float(acceleration)
    if D <= 0:
        return Profile(0.0, np.zeros(1), np.zeros(1), np.zeros(1))
    if D <= v * v / a:  # triangular: the cruise speed is never reached
        Ta = np.sqrt(D / a)
        Tv = 0.0
    else:
        Ta = v / a
        Tv = (D - v * v / a) / v
    return Profile(D, np.array([Ta, Tv, Ta]), np.array([a, 0.0, -a]), np.zeros(3))


def double_s(distance: float, speed: float, acceleration: float, jerk: float) -> Profile:
    """Minimum-time rest-to-rest jerk-limited ("double S") profile.

    Symmetric acceleration and deceleration (Biagiotti & Melchiorri 2008,
    section 3.4); when the distance is too short for the cruise speed, the
    peak speed is lowered (bisection) until the two ramps meet.
    """
    D, vmax, amax, jmax = float(distance), float(speed), float(acceleration), float(jerk)
    if D <= 0:
        return Profile(0.0, np.zeros(1), np.zeros(1), np.zeros(1))

    def ramp(vp):
        if vp * jmax <= amax * amax:  # the acceleration limit is not reached
            Tj = np.sqrt(vp / jmax)
            return Tj, 2 * Tj, jmax * Tj
        Tj = amax / jmax
        return Tj, vp / amax + Tj, amax

    Tj, Ta, ap = ramp(vmax)
    if vmax * Ta <= D:  # two ramps cover vmax * Ta / 2 each
        vp = vmax
    else:
        lo, hi = 0.0, vmax
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            Tj, Ta, ap = ramp(mid)
            if mid * Ta > D:
                hi = mid
            else:
                lo = mid
        vp = lo
        Tj, Ta, ap = ramp(vp)
    Tv = max(D - vp * Ta, 0.0) / vp
    Tc = max(Ta - 2 * Tj, 0.0)
    j = jmax if Tj > 0 else 0.0
    ap = j * Tj
    durations = np.array([Tj, Tc, Tj, Tv, Tj, Tc, Tj])
    a0 = np.array([0.0, ap, ap, 0.0, 0.0, -ap, -ap])
    jk = np.array([j, 0.0, -j, 0.0, -j, 0.0, j])
    return Profile(D, durations, a0, jk)


def fit_to_cycle(profile: Profile, cycle_time: float) -> Profile:
    """Stretch a profile in time so its duration is a whole number of cycles.

    Uniform time scaling by lambda = N dt / T >= 1 divides speed by lambda,
    acceleration by lambda^2 and jerk by lambda^3: every limit still holds.
    """
    T = profile.raw_duration
    if T <= 0:
        return profile
    N = max(int(np.ceil(T / cycle_time - 1e-9)), 1)
    return Profile(profile.distance, profile.durations, profile.a0, profile.jerk,
                   scale=N * cycle_time / T)


def _profile(traj: Trajectory, distance: float, speed: float, accel: float) -> Profile:
    if traj.jerk is not None:
        return double_s(distance, speed, accel, traj.jerk)
    return trapezoid(distance, speed, accel)


# ----------------------------------------------------------------------------
# Paths
# ----------------------------------------------------------------------------


def _fixed_orientation(design: Design, traj: Trajectory) -> np.ndarray:
    rc = design.motion.rotation_coords
    if not rc:
        return np.zeros(0)
    if traj.orientation is not None:
        return np.asarray(traj.orientation, float)
    if design.workspace.orientation:
        return np.asarray(design.workspace.orientation, float)
    return np.zeros(len(rc))


def _as_pose(design: Design, point, ori) -> np.ndarray:
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
    :func:`sample`).
    """
    ori = _fixed_orientation(design, traj)
    if traj.type == "square":
        c = np.asarray(traj.center, float)
        h = traj.side / 2
        offs = np.array([[-h, -h], [h, -h], [h, h], [-h, h], [-h, -h]])
        pts = []
        for o in offs:
            q = c.copy()
            q[:2] = c[:2] + o
            pts.append(_as_pose(design, q, ori))
        base = np.array(pts)
        closed = True
    elif traj.type in ("polyline", "csv"):
        src = traj.waypoints if traj.type == "polyline" else csv_poses
        if src is None:
            raise ValueError(f"trajectory {traj.name!r}: a csv path needs its poses (csv_poses)")
        src = np.atleast_2d(np.asarray(src, float))
        if src.shape[0] < 2:
            raise ValueError(f"trajectory {traj.name!r}: expected at least 2 poses, got {src.shape[0]}")
        base = np.array([_as_pose(design, w, ori) for w in src])
        closed = bool(np.allclose(base[0], base[-1]))
    else:
        raise ValueError(f"trajectory {traj.name!r}: no corner list for a {traj.type} path")
    out = [base]
    for _lap in range(1, traj.laps):
        if not closed:
            out.append(base[:1])  # closing segment back to the start
        out.append(base[1:])
    return np.vstack(out)


# ----------------------------------------------------------------------------
# Sampling
# ----------------------------------------------------------------------------


def _seg_length(design: Design, p0, p1) -> float:
    d = design.motion.dim
    dp = p1 - p0
    L = float(np.linalg.norm(dp[:d]))
    if L == 0.0:
        L = float(np.linalg.norm(dp[d:]))  # pure rotation: length in rad
    return L


def _line_samples(design, traj, p0, p1, dt, speed, accel):
    D = _seg_length(design, p0, p1)
    if D == 0.0:
        return None
    prof = fit_to_cycle(_profile(traj, D, speed, accel), dt)
    N = int(round(prof.duration / dt))
    t = dt * np.arange(1, N + 1)
    s, v, a = prof.evaluate(t)
    e = (p1 - p0) / D
    pose = p0[None, :] + s[:, None] * e[None, :]
    pose[-1] = p1  # exactly on the waypoint
    return pose, v[:, None] * e[None, :], a[:, None] * e[None, :]


def _circle_samples(design, traj, dt, start_angle=0.0):
    r = float(traj.radius)
    c = np.asarray(traj.center, float)
    ori = _fixed_orientation(design, traj)
    at = traj.acceleration / np.sqrt(2.0)
    vc = min(traj.speed, np.sqrt(traj.acceleration * r / np.sqrt(2.0)))
    D = 2 * np.pi * r * traj.laps
    prof = fit_to_cycle(_profile(traj, D, vc, at), dt)
    N = int(round(prof.duration / dt))
    t = dt * np.arange(0, N + 1)
    s, v, a = prof.evaluate(t)
    th = start_angle + s / r
    nc = len(design.motion.coords)
    pose = np.zeros((t.size, nc))
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


def sample(design: Design, trajectory: str | Trajectory, cycle_time: float | None = None, *,
           csv_poses=None, hold_start: float = 0.0, hold_end: float = 0.0,
           external=None) -> Samples:
    """Sample a trajectory of the design at a fixed cycle time.

    Parameters
    ----------
    design : Design
    trajectory : str or Trajectory
        A name of ``design.trajectories`` or a Trajectory object.
    cycle_time : float, optional
        Sample period [s]; default: the trajectory's ``cycle_time``, else 1 ms.
    csv_poses : (q, dim or ncoords) array, optional
        The poses of a ``csv`` path (read by the caller; the core reads no file).
    hold_start, hold_end : float
        Time [s] to stand still at the first and last pose (e.g. to let a
        simulation settle); rounded to whole cycles.
    external : (n,) array, optional
        Constant external wrench on the effector [N, N m] (motion's rows).

    Returns
    -------
    Samples

    Raises
    ------
    KeyError
        Unknown trajectory name.
    ValueError
        A csv path without its poses, or bad poses.
    """
    if isinstance(trajectory, str):
        if trajectory not in design.trajectories:
            known = ", ".join(sorted(design.trajectories)) or "none"
            raise KeyError(f"no trajectory named {trajectory!r} (known: {known})")
        traj = design.trajectories[trajectory]
    else:
        traj = trajectory
    dt = float(cycle_time or traj.cycle_time or DEFAULT_CYCLE_TIME)
    if not dt > 0:
        raise ValueError(f"cycle_time must be > 0, got {dt}")
    ori = _fixed_orientation(design, traj)

    poses, vels, accs, segid = [], [], [], []
    segments: list[Segment] = []

    def add_block(kind, p, v, a, p0, p1):
        idx = len(segments)
        first = sum(x.shape[0] for x in poses)
        poses.append(p)
        vels.append(v)
        accs.append(a)
        segid.append(np.full(p.shape[0], idx))
        segments.append(Segment(idx, kind, np.asarray(p0), np.asarray(p1), first - 1,
                                first + p.shape[0] - 1))

    if traj.type == "circle":
        c = np.asarray(traj.center, float)
        first_pt = c.copy()
        first_pt[0] += traj.radius
        first_pose = _as_pose(design, first_pt, ori)
    else:
        corners = path_waypoints(design, traj, csv_poses)
        first_pose = corners[0]
    start = _as_pose(design, traj.start, ori) if traj.start is not None else first_pose
    nc = len(design.motion.coords)
    # sample 0: the start pose, at rest
    poses.append(start[None, :].copy())
    vels.append(np.zeros((1, nc)))
    accs.append(np.zeros((1, nc)))
    segid.append(np.zeros(1, dtype=int))
    if hold_start > 0:
        h = int(round(hold_start / dt))
        poses.append(np.repeat(start[None, :], h, axis=0))
        vels.append(np.zeros((h, nc)))
        accs.append(np.zeros((h, nc)))
        segid.append(np.zeros(h, dtype=int))
    if not np.allclose(start, first_pose):
        blk = _line_samples(design, traj, start, first_pose, dt, traj.speed, traj.acceleration)
        if blk is not None:
            add_block("approach", *blk, start, first_pose)
    if traj.type == "circle":
        p, v, a = _circle_samples(design, traj, dt)
        add_block("arc", p[1:], v[1:], a[1:], first_pose, first_pose)
    else:
        for q in range(corners.shape[0] - 1):
            blk = _line_samples(design, traj, corners[q], corners[q + 1], dt, traj.speed,
                                traj.acceleration)
            if blk is not None:
                add_block("line", *blk, corners[q], corners[q + 1])
    last = len(segments) - 1 if segments else 0
    if hold_end > 0:
        h = int(round(hold_end / dt))
        end = poses[-1][-1]
        poses.append(np.repeat(end[None, :], h, axis=0))
        vels.append(np.zeros((h, nc)))
        accs.append(np.zeros((h, nc)))
        segid.append(np.full(h, max(last, 0)))

    pose = np.vstack(poses)
    vel = np.vstack(vels)
    acc = np.vstack(accs)
    seg = np.concatenate(segid).astype(np.int64)
    if segments:  # the hold at the start belongs to the first segment
        seg[: segments[0].first + 1] = 0
    time = dt * np.arange(pose.shape[0])
    st = states(design, pose, vel, acc, time=time, external=external)
    L0 = st["lengths"][0]
    r = np.array([c.winch.drum_radius for c in design.cables])
    gr = np.array([c.winch.gear_ratio for c in design.cables])
    motor = (st["lengths"] - L0[None, :]) / r[None, :] * gr[None, :]
    return Samples(
        name=traj.name, coords=tuple(design.motion.coords), cable_names=tuple(design.cable_names),
        time=time, pose=pose, velocity=vel, acceleration=acc, lengths=st["lengths"],
        cable_speed=st["cable_speed"], cable_accel=st["cable_accel"], motor_angle=motor,
        tensions=st["tensions"], feasible=st["feasible"], segment=seg,
        segments=tuple(segments), cycle_time=dt,
    )


# ----------------------------------------------------------------------------
# Kinematics and dynamics along a sampled path (vectorised)
# ----------------------------------------------------------------------------


def _rotations(angles: np.ndarray) -> np.ndarray:
    """R = Rx(a) Ry(b) Rz(c) for (k, 3) angles -> (k, 3, 3)."""
    a, b, c = angles[:, 0], angles[:, 1], angles[:, 2]
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    k = angles.shape[0]
    R = np.empty((k, 3, 3))
    R[:, 0, 0] = cb * cc
    R[:, 0, 1] = -cb * sc
    R[:, 0, 2] = sb
    R[:, 1, 0] = ca * sc + sa * sb * cc
    R[:, 1, 1] = ca * cc - sa * sb * sc
    R[:, 1, 2] = -sa * cb
    R[:, 2, 0] = sa * sc - ca * sb * cc
    R[:, 2, 1] = sa * cc + ca * sb * sc
    R[:, 2, 2] = ca * cb
    return R


def _omega(angles: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """Angular velocity (frame) of Rx(a) Ry(b) Rz(c) for angle rates, (k, 3)."""
    a, b = angles[:, 0], angles[:, 1]
    ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    ex = np.stack([np.ones_like(a), 0 * a, 0 * a], axis=1)
    ey = np.stack([0 * a, ca, sa], axis=1)  # Rx(a) e_y
    ez = np.stack([sb, -sa * cb, ca * cb], axis=1)  # Rx(a) Ry(b) e_z
    return rates[:, :1] * ex + rates[:, 1:2] * ey + rates[:, 2:3] * ez


def _full(design: Design, x: np.ndarray) -> np.ndarray:
    out = np.zeros((x.shape[0], 6))
    out[:, list(design.motion.pose_index)] = x
    return out


def solve_tensions(design: Design, W: np.ndarray, wreq: np.ndarray) -> np.ndarray:
    """Cable tensions for many poses: W t = w_req, (k, n, m), (k, n) -> (k, m) [N].

    m = n: t = W^-1 w_req (the paper's eq. 6 solved directly), NaN where W is
    singular.  m > n: the minimum 2-norm tensions within the cable bounds,
    min 1/2 |t|^2 s.t. W t = w_req, t_min <= t <= t_max (the compiled
    active-set kernel ``_kernels.min_norm_tensions`` when present, else
    scipy's SLSQP), NaN where the bounds admit none.  m < n: the
    least-squares solution where it balances w_req exactly, else NaN.
    """
    k, n, m = W.shape
    t = np.full((k, m), np.nan)
    if m == n:
        det = np.linalg.det(W)
        scale = np.prod(np.linalg.norm(W, axis=2), axis=1)
        ok = np.abs(det) > 1e-10 * np.maximum(scale, 1e-300)
        if np.any(ok):
            t[ok] = np.linalg.solve(W[ok], wreq[ok][:, :, None])[:, :, 0]
        return t
    tmin, tmax = design.tension_min, design.tension_max
    if m > n:
        kern = _min_norm_kernel()
        if kern is not None:
            solve, scratch = kern
            scr = scratch(n, m, 1)
            out = np.empty(m)
            for i in range(k):
                Wi = np.ascontiguousarray(W[i])
                if solve(Wi, np.ascontiguousarray(wreq[i]), tmin, tmax, out, scr):
                    t[i] = out
            return t
        return _min_norm_slsqp(W, wreq, tmin, tmax)
    for i in range(k):
        sol, *_ = np.linalg.lstsq(W[i], wreq[i], rcond=None)
        if np.linalg.norm(W[i] @ sol - wreq[i]) <= 1e-8 * (1 + np.linalg.norm(wreq[i])):
            t[i] = sol
    return t


def _min_norm_kernel():
    """(min_norm_tensions, make_scratch) of the compiled kernels, when they exist."""
    from cdpr_design import kernels as K

    f, s = getattr(K, "min_norm_tensions", None), getattr(K, "make_scratch", None)
    return (f, s) if callable(f) and callable(s) else None


def _min_norm_slsqp(W, wreq, tmin, tmax) -> np.ndarray:
    """Slow reference: min |t|^2 s.t. W t = w, bounds, by SLSQP per pose (NaN where it fails)."""
    from scipy.optimize import minimize

    k, n, m = W.shape
    t = np.full((k, m), np.nan)
    for i in range(k):
        x0 = np.clip(np.linalg.lstsq(W[i], wreq[i], rcond=None)[0], tmin, tmax)
        res = minimize(lambda x: 0.5 * x @ x, x0, jac=lambda x: x, method="SLSQP",
                       bounds=list(zip(tmin, tmax)),
                       constraints=[{"type": "eq", "fun": lambda x, i=i: W[i] @ x - wreq[i],
                                     "jac": lambda x, i=i: W[i]}],
                       options={"ftol": 1e-12, "maxiter": 200})
        if res.success and np.linalg.norm(W[i] @ res.x - wreq[i]) <= 1e-6 * (1 + np.linalg.norm(wreq[i])):
            t[i] = res.x
    return t


def states(design: Design, pose, velocity, acceleration, *, time=None, external=None) -> dict:
    """Cable lengths, speeds, accelerations and inertial tensions along a path.

    Parameters
    ----------
    design : Design
    pose, velocity, acceleration : (k, ncoords) arrays
        Pose [m, rad] and its time derivatives (angle rates for rotations).
    time : (k,) array, optional
        Sample times [s]; needed for the angular acceleration of rotational
        motions (finite difference of the angular velocity).
    external : (n,) array, optional
        External wrench [N, N m], motion's rows.

    Returns
    -------
    dict with ``lengths``, ``cable_speed``, ``cable_accel``, ``tensions`` (k, m)
    and ``feasible`` (k,).

    Notes
    -----
    l_i = a_i - (p + R b_i) (paper eq. 1), L_i = |l_i|, u_i = l_i / L_i;
    with the attachment point's velocity v_B = v + w x R b_i and acceleration
    a_B = a + alpha x R b_i + w x (w x R b_i):
    dL/dt = -u . v_B and d2L/dt2 = (|v_B|^2 - (dL/dt)^2) / L - u . a_B.
    Tensions solve W t = -(w_gravity + w_inertial + w_external) with the
    d'Alembert wrench w_inertial = -(m a_c, I alpha + w x I w) (paper eq. 6-9
    with the inertia added).

    Swivel pulleys (``cables[i].pulley``, :mod:`cdpr_design.statics.pulley`): L_i is
    the arc + free length, u_i the free segment's unit vector from the
    attachment towards the pulley's tangent point (the gradient of L_i is
    -u_i, so dL/dt = -u . v_B still holds and W keeps its form), and
    d2L/dt2 = v_B^T H v_B - u . a_B with the pulley-aware Hessian H of
    :func:`cdpr_design.statics.pulley.cable_paths` (1 / l_f in the pulley plane,
    the swivel curvature across it).
    """
    x = np.atleast_2d(np.asarray(pose, float))
    xd = np.atleast_2d(np.asarray(velocity, float))
    xdd = np.atleast_2d(np.asarray(acceleration, float))
    k = x.shape[0]
    P, V, Acc = _full(design, x), _full(design, xd), _full(design, xdd)
    rotational = design.motion.rotational
    A, B = design.outlets, design.attachments
    if rotational:
        R = _rotations(P[:, 3:])
        w = _omega(P[:, 3:], V[:, 3:])
        if design.motion.name == "1R2T":
            al = np.zeros((k, 3))
            al[:, 2] = Acc[:, 5]  # rotation about z only: alpha = phi''
        elif time is not None and k > 1:
            al = np.gradient(w, np.asarray(time, float), axis=0)
        else:
            al = np.zeros((k, 3))
    else:
        R = np.broadcast_to(np.eye(3), (k, 3, 3))
        w = np.zeros((k, 3))
        al = np.zeros((k, 3))
    Rb = np.einsum("kij,mj->kmi", R, B)  # (k, m, 3)
    vB = V[:, None, :3] + np.cross(w[:, None, :], Rb)
    aB = Acc[:, None, :3] + np.cross(al[:, None, :], Rb) + np.cross(w[:, None, :], np.cross(w[:, None, :], Rb))
    if pl.any_pulley(design):
        # swivel pulleys: arc + free length, u along the free segment from the tangent point
        paths = pl.design_cable_paths(design, P[:, None, :3] + Rb)
        L = paths.lengths
        u = np.nan_to_num(paths.directions)
        Ld = -np.einsum("kmi,kmi->km", u, vB)
        Ldd = paths.second_derivative(vB) - np.einsum("kmi,kmi->km", u, aB)
    else:
        vec = A[None, :, :] - P[:, None, :3] - Rb
        L = np.linalg.norm(vec, axis=2)
        with np.errstate(invalid="ignore", divide="ignore"):
            u = vec / L[:, :, None]
        u = np.nan_to_num(u)
        Ld = -np.einsum("kmi,kmi->km", u, vB)
        with np.errstate(invalid="ignore", divide="ignore"):
            Ldd = (np.einsum("kmi,kmi->km", vB, vB) - Ld ** 2) / L - np.einsum("kmi,kmi->km", u, aB)
    # wrenches
    rows = list(design.motion.wrench_rows)
    Wfull = np.concatenate([u, np.cross(Rb, u)], axis=2)  # (k, m, 6)
    W = np.transpose(Wfull[:, :, rows], (0, 2, 1))  # (k, n, m)
    m_eff = design.effector.mass
    c = np.einsum("kij,j->ki", R, np.asarray(design.effector.center_of_mass, float))
    g = np.asarray(design.gravity, float)
    f_g = np.broadcast_to(m_eff * g, (k, 3))
    a_c = Acc[:, :3] + np.cross(al, c) + np.cross(w, np.cross(w, c))
    f_i = -m_eff * a_c
    I0 = design.effector.inertia_matrix
    I = np.einsum("kij,jl,kml->kim", R, I0, R)
    Iw = np.einsum("kij,kj->ki", I, w)
    tau_i = -(np.einsum("kij,kj->ki", I, al) + np.cross(w, Iw))
    f = f_g + f_i
    mom = np.cross(c, f) + tau_i
    wext = np.concatenate([f, mom], axis=1)[:, rows]
    if external is not None:
        wext = wext + np.asarray(external, float)[None, :]
    t = solve_tensions(design, W, -wext)
    tmin, tmax = design.tension_min, design.tension_max
    with np.errstate(invalid="ignore"):
        feas = np.all(np.isfinite(t), axis=1) & np.all(t >= tmin - TENSION_TOL, axis=1) \
            & np.all(t <= tmax + TENSION_TOL, axis=1)
    return {"lengths": L, "cable_speed": Ld, "cable_accel": Ldd, "tensions": t, "feasible": feas,
            "structure": W}


def pose_at(samples: Samples, time) -> np.ndarray:
    """Linear interpolation of the sampled pose at given times [s] (clamped at the ends)."""
    time = np.asarray(time, float)
    return np.stack([np.interp(time, samples.time, samples.pose[:, j])
                     for j in range(samples.pose.shape[1])], axis=-1)


__all__ = [
    "DEFAULT_CYCLE_TIME", "Profile", "Samples", "Segment", "double_s", "fit_to_cycle",
    "path_waypoints", "pose_at", "sample", "solve_tensions", "states", "trapezoid",
]
