"""Trajectory sampling: per-sample axis set-points, tensions and feasibility.

A named path of the spec's ``trajectories:`` section (square, polyline,
circle, or a table of poses; :mod:`cdpr_design.motion.paths`) is sampled at
a fixed cycle time (default 1 ms, a PLC cycle) with a rest-to-rest speed
profile on every straight segment (trapezoidal, or jerk-limited "S-curve"
when ``jerk`` is given; :mod:`cdpr_design.motion.profile`) and one profile
over the whole arc of a circle.  Every sample carries what a winch
controller and a sizing study need: the pose and its derivatives, the cable
lengths, speeds and accelerations, the motor angles and the cable tensions
that hold the effector *with its inertia* (d'Alembert), and a feasibility flag.

Conventions
-----------
- Straight segments start and end at rest, so the path never cuts a corner
  and the effector never flies ballistic at a corner (a cable robot cannot pull
  downwards faster than gravity).  Each segment's duration is stretched to a
  whole number of cycles, so a sample falls *exactly* on every waypoint.
- ``start`` (when it differs from the path's first point) adds a straight
  approach segment.
- Motor angle: ``theta_i = (L_i - L_i(0)) / r_i * gear_ratio_i`` [rad], zero
  at the trajectory's first sample (the homed position), positive when cable is
  paid out (the cable gets longer).

References
----------
Rivera, Garrido, Riveiro, Silva: "Environment for the Design and Automation
of New CDPR Architectures" (the seed paper), section 4: the square test path
at 100 and 1000 mm/s; eq. (1)-(3) inverse kinematics; eq. (6)-(9) statics.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cdpr_design.model.design import Design, Trajectory
from cdpr_design.motion import paths, setpoints
from cdpr_design.motion.profile import MAX_SAMPLES, too_many_samples
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.degenerate import degenerate
from cdpr_design.statics.robot import Robot, tension_lower

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
    cables : setpoints.CableSamples or None
        With elastic or sagging cables: the unstretched lengths (the
        set-points), the error of ideal set-points, outlet tensions, sag and
        status per sample (:mod:`cdpr_design.motion.setpoints`); then
        ``tensions`` are at the effector end and ``feasible`` holds the bounds
        along the whole cable.  None for ideal cables.
    interference : (k,) uint8 array or None
        With the analysis's ``collisions``: each sample's interference bits
        (:func:`cdpr_design.statics.interference.path_interference`; 0 collision free), and
        ``feasible`` is then collision free too.  None without.
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
    cables: object = None
    interference: np.ndarray | None = None

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
        if self.cables is not None:
            out.update(self.cables.columns(self.cable_names))
        if self.interference is not None:
            out["collision_free"] = (self.interference == 0).astype(np.int64)
        return out

    def summary(self) -> dict:
        """Headline figures (JSON-ready)."""
        speed = np.linalg.norm(self.velocity[:, : _pos_dim(self.coords)], axis=1)
        acc = np.linalg.norm(self.acceleration[:, : _pos_dim(self.coords)], axis=1)
        with np.errstate(invalid="ignore"):
            out = {
                "name": self.name,
                "samples": int(self.time.size),
                "duration": self.duration,
                "cycle_time": self.cycle_time,
                "feasible": self.all_feasible,
                "infeasible_samples": int(np.count_nonzero(~self.feasible)),
                "max_speed": float(speed.max()) if speed.size else 0.0,
                "max_acceleration": float(acc.max()) if acc.size else 0.0,
                "max_tension": _column_extreme(self.tensions, self.cable_names, np.max),
                "min_tension": _column_extreme(self.tensions, self.cable_names, np.min),
                "max_cable_speed": dict(zip(self.cable_names, map(float, np.abs(self.cable_speed).max(axis=0)))),
                "segments": len(self.segments),
            }
        if self.cables is not None:
            out.update(self.cables.summary(self.cable_names))
        if self.interference is not None:
            from cdpr_design.statics.interference import HIT_NAMES

            out["collision_samples"] = int(np.count_nonzero(self.interference))
            out["collisions_by_kind"] = {name: int(np.count_nonzero(self.interference & bit))
                                         for bit, name in HIT_NAMES.items()}
        return out


def _column_extreme(values, names, pick) -> dict:
    """``pick`` (np.max or np.min) of each column of ``values`` (samples, cables) [N] over its
    samples that are not NaN, by cable name; None where a cable has none (or the answer is not
    finite).  Unlike np.nanmax, no warning for a column that is NaN throughout."""
    out = {}
    for j, name in enumerate(names):
        col = values[:, j]
        col = col[~np.isnan(col)]
        v = pick(col) if col.size else np.nan
        out[name] = float(v) if np.isfinite(v) else None
    return out



def _pos_dim(coords) -> int:
    return sum(1 for c in coords if c in ("x", "y", "z"))


# ----------------------------------------------------------------------------
# Sampling
# ----------------------------------------------------------------------------


class _Blocks:
    """The samples of a path (pose, velocity, acceleration, segment id), assembled in time order."""

    def __init__(self, ncoords: int):
        self.nc = ncoords
        self.poses: list[np.ndarray] = []
        self.vels: list[np.ndarray] = []
        self.accs: list[np.ndarray] = []
        self.segid: list[np.ndarray] = []
        self.segments: list[Segment] = []
        self.total = 0

    def _grow(self, n: int) -> None:
        """Count ``n`` more samples; a ValueError past :data:`~cdpr_design.motion.profile.MAX_SAMPLES`."""
        self.total += n
        if self.total > MAX_SAMPLES:
            raise ValueError(too_many_samples(self.total))

    @property
    def count(self) -> int:
        """Samples so far."""
        return sum(x.shape[0] for x in self.poses)

    @property
    def last_pose(self) -> np.ndarray:
        return self.poses[-1][-1]

    def rest(self, pose, count: int, segment: int) -> None:
        """``count`` samples standing still at ``pose``, counted in segment ``segment``."""
        self._grow(count)
        self.poses.append(np.repeat(pose[None, :], count, axis=0))
        self.vels.append(np.zeros((count, self.nc)))
        self.accs.append(np.zeros((count, self.nc)))
        self.segid.append(np.full(count, segment, dtype=int))

    def move(self, kind: str, block, p0, p1) -> None:
        """A new segment from p0 to p1 sampled as ``block`` = (pose, velocity, acceleration)
        (p0 excluded); nothing when ``block`` is None (a segment of zero length)."""
        if block is None:
            return
        p, v, a = block
        self._grow(p.shape[0])
        idx = len(self.segments)
        first = self.count
        self.poses.append(p)
        self.vels.append(v)
        self.accs.append(a)
        self.segid.append(np.full(p.shape[0], idx))
        self.segments.append(Segment(idx, kind, np.asarray(p0), np.asarray(p1), first - 1,
                                     first + p.shape[0] - 1))

    def stack(self):
        """(pose, velocity, acceleration) (k, ncoords) arrays and segment ids (k,)."""
        seg = np.concatenate(self.segid).astype(np.int64)
        if self.segments:  # the hold at the start belongs to the first segment
            seg[: self.segments[0].first + 1] = 0
        return np.vstack(self.poses), np.vstack(self.vels), np.vstack(self.accs), seg


def _lookup(design: Design, trajectory: str | Trajectory) -> Trajectory:
    if not isinstance(trajectory, str):
        return trajectory
    if trajectory not in design.trajectories:
        known = ", ".join(sorted(design.trajectories)) or "none"
        raise KeyError(f"no trajectory named {trajectory!r} (known: {known})")
    return design.trajectories[trajectory]


def _path_blocks(design: Design, traj: Trajectory, dt: float, csv_poses,
                 hold_start: float, hold_end: float, line=paths.line_samples, arc=None) -> _Blocks:
    """The samples of the whole path every ``dt`` [s]: start, holds, approach, segments (each
    sampled by ``line``) or arc (sampled by ``arc``; :func:`sample`)."""
    ori = paths.fixed_orientation(design, traj)
    corners = None if traj.type == "circle" else paths.path_waypoints(design, traj, csv_poses)
    first = paths.first_pose(design, traj, corners)
    start = paths.as_pose(design, traj.start, ori) if traj.start is not None else first
    blocks = _Blocks(len(design.motion.coords))
    blocks.rest(start, 1, 0)  # sample 0: the start pose, at rest
    if hold_start > 0:
        blocks.rest(start, int(round(hold_start / dt)), 0)
    if not np.allclose(start, first):
        blocks.move("approach", line(design, traj, start, first, dt), start, first)
    if traj.type == "circle":
        blocks.move("arc", (arc or _profiled_arc)(design, traj, dt), first, first)
    else:
        for q in range(corners.shape[0] - 1):
            blocks.move("line", line(design, traj, corners[q], corners[q + 1], dt),
                        corners[q], corners[q + 1])
    if hold_end > 0:
        blocks.rest(blocks.last_pose, int(round(hold_end / dt)), max(len(blocks.segments) - 1, 0))
    return blocks


def _profiled_arc(design: Design, traj: Trajectory, dt: float):
    """The circle's samples along its own profile, its start excluded (:func:`sample`'s ``arc``)."""
    p, v, a = paths.circle_samples(design, traj, dt)
    return p[1:], v[1:], a[1:]


def motor_angles(design: Design, lengths) -> np.ndarray:
    """Motor shaft angles [rad] for cable lengths (k, m) [m], zero at the first sample:
    theta_i = (L_i - L_i(0)) / r_i * gear_ratio_i (r_i the drum radius)."""
    L0 = lengths[0]
    r = np.array([c.winch.drum_radius for c in design.cables])
    gr = np.array([c.winch.gear_ratio for c in design.cables])
    return (lengths - L0[None, :]) / r[None, :] * gr[None, :]


def sample(robot: Robot, trajectory: str | Trajectory, cycle_time: float | None = None, *,
           csv_poses=None, hold_start: float = 0.0, hold_end: float = 0.0,
           external=None, line=None, arc=None) -> Samples:
    """Sample a trajectory of the robot's design at a fixed cycle time.

    Parameters
    ----------
    robot : Robot
        The design resolved for ``motion`` (:func:`~cdpr_design.statics.robot.resolve`).
    trajectory : str or Trajectory
        A name of the design's ``trajectories`` or a Trajectory object.
    cycle_time : float, optional
        Sample period [s]; default: the trajectory's ``cycle_time``, else 1 ms.
    csv_poses : (q, dim or ncoords) array, optional
        The poses of a ``csv`` path (read by the caller; the core reads no file).
    hold_start, hold_end : float
        Time [s] to stand still at the first and last pose (e.g. to let a
        simulation settle); rounded to whole cycles.
    external : (n,) array, optional
        Constant external wrench on the effector [N, N m] (motion's rows).
    line : callable, optional
        ``line(design, traj, p0, p1, dt)`` -> (pose, velocity, acceleration) (N, ncoords) arrays of
        the straight segment p0 -> p1 from rest to rest, p0 excluded (None: zero length); default
        the path's speed profile (:func:`cdpr_design.motion.paths.line_samples`);
        :mod:`cdpr_design.motion.time_optimal` passes its own.
    arc : callable, optional
        ``arc(design, traj, dt)`` -> (pose, velocity, acceleration) (N, ncoords) arrays of a circle
        path, all its laps from rest to rest, its start excluded; default the path's speed profile
        (:func:`cdpr_design.motion.paths.circle_samples`); :mod:`cdpr_design.motion.time_optimal`
        passes its own.

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
    design = robot.design
    traj = _lookup(design, trajectory)
    dt = float(cycle_time or traj.cycle_time or DEFAULT_CYCLE_TIME)
    if not dt > 0:
        raise ValueError(f"cycle_time must be > 0, got {dt}")
    blocks = _path_blocks(design, traj, dt, csv_poses, hold_start, hold_end, line or paths.line_samples, arc)
    pose, vel, acc, seg = blocks.stack()
    time = dt * np.arange(pose.shape[0])
    st = states(robot, pose, vel, acc, external=external)
    cs, tensions, feasible = setpoints.cable_samples(robot, st["positions"], st["attachments"], st["wrench"],
                                                     st["lengths"], st["tensions"], st["feasible"])
    mask = None
    if robot.analysis.collisions:
        from cdpr_design.statics.interference import path_interference

        mask = path_interference(robot, pose, None if cs is None else cs.unstretched)
        feasible = feasible & (mask == 0)
    return Samples(
        name=traj.name, coords=tuple(design.motion.coords), cable_names=tuple(design.cable_names),
        time=time, pose=pose, velocity=vel, acceleration=acc, lengths=st["lengths"],
        cable_speed=st["cable_speed"], cable_accel=st["cable_accel"],
        motor_angle=motor_angles(design, st["lengths"]), tensions=tensions,
        feasible=feasible, segment=seg, segments=tuple(blocks.segments), cycle_time=dt, cables=cs,
        interference=mask,
    )


# ----------------------------------------------------------------------------
# Kinematics and statics along a sampled path (vectorised over the samples)
# ----------------------------------------------------------------------------


def _full(design: Design, x: np.ndarray) -> np.ndarray:
    """Poses (or their derivatives) in the motion's coordinates (k, ncoords) as (k, 6) rows."""
    out = np.zeros((x.shape[0], 6))
    out[:, list(design.motion.pose_index)] = x
    return out


def _rotations(angles: np.ndarray) -> np.ndarray:
    """R = Rx(a) Ry(b) Rz(c) for (k, 3) angles [rad] -> (k, 3, 3).

    :func:`cdpr_design.statics.kinematics.rotation_matrix` for k poses at once
    (in closed form: its matrix products would round differently).
    """
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


def _body_rotation(design: Design, P, V, Acc):
    """Rotation matrices (k, 3, 3), angular velocities and accelerations (k, 3) [rad/s, rad/s^2]
    of the poses ``P``, their rates ``V`` and second derivatives ``Acc`` (k, 6): exact, from the
    Euler angles' derivatives (:func:`cdpr_design.statics.kinematics.euler_motion`)."""
    k = P.shape[0]
    if not design.motion.rotational:
        return np.broadcast_to(np.eye(3), (k, 3, 3)), np.zeros((k, 3)), np.zeros((k, 3))
    w, al = kin.euler_motion(P[:, 3:], V[:, 3:], Acc[:, 3:])
    return _rotations(P[:, 3:]), w, al


def _cable_motion(robot: Robot, P, Rb, vB, aB):
    """Lengths L [m], free lengths [m] (tangent point, or outlet, to attachment), pulling
    directions u, dL/dt [m/s] and d2L/dt2 [m/s^2] of every cable.

    ``P`` (k, 6) poses, ``Rb`` (k, m, 3) rotated attachments, ``vB`` and
    ``aB`` (k, m, 3) the attachment points' velocities and accelerations.
    """
    return robot.outlets.motion_paths(robot.design, P[:, :3], Rb, vB, aB)


def _structure(design: Design, u, Rb) -> np.ndarray:
    """Structure matrices W (k, n, m): columns [u_i ; R b_i x u_i] on the motion's wrench rows
    (:func:`cdpr_design.statics.kinematics.structure_matrix` for k poses at once)."""
    Wfull = np.concatenate([u, np.cross(Rb, u)], axis=2)  # (k, m, 6)
    return np.transpose(Wfull[:, :, list(design.motion.wrench_rows)], (0, 2, 1))


def _load_wrenches(design: Design, R, Acc, w, al, external) -> np.ndarray:
    """Gravity + d'Alembert inertia + external wrench on the effector (k, n) [N, N m].

    The vectorised sum of :func:`cdpr_design.statics.kinematics.gravity_wrench`
    and :func:`~cdpr_design.statics.kinematics.inertial_wrench` (plus
    ``external``) over the samples; the cables balance its opposite.
    """
    k = Acc.shape[0]
    m_eff = design.effector.mass
    c = np.einsum("kij,j->ki", R, np.asarray(design.effector.center_of_mass, float))
    f_g = np.broadcast_to(m_eff * np.asarray(design.gravity, float), (k, 3))
    a_c = Acc[:, :3] + np.cross(al, c) + np.cross(w, np.cross(w, c))
    f_i = -m_eff * a_c
    I = np.einsum("kij,jl,kml->kim", R, design.effector.inertia_matrix, R)
    Iw = np.einsum("kij,kj->ki", I, w)
    tau_i = -(np.einsum("kij,kj->ki", I, al) + np.cross(w, Iw))
    f = f_g + f_i
    wext = np.concatenate([f, np.cross(c, f) + tau_i], axis=1)[:, list(design.motion.wrench_rows)]
    if external is not None:
        wext = wext + np.asarray(external, float)[None, :]
    return wext


def within_bounds(design: Design, tensions, lower=None) -> np.ndarray:
    """Feasibility flags (k,): tensions (k, m) finite and within every cable's bounds
    (to :data:`TENSION_TOL` [N]); ``lower`` (k, m) [N] the samples' lower bounds (default
    ``tension_min``; :func:`~cdpr_design.statics.robot.tension_lower`)."""
    tmin, tmax = design.tension_min if lower is None else lower, design.tension_max
    with np.errstate(invalid="ignore"):
        return np.all(np.isfinite(tensions), axis=1) & np.all(tensions >= tmin - TENSION_TOL, axis=1) \
            & np.all(tensions <= tmax + TENSION_TOL, axis=1)


def solve_tensions(design: Design, W: np.ndarray, wreq: np.ndarray, lower=None) -> np.ndarray:
    """Cable tensions for many poses: W t = w_req, (k, n, m), (k, n) -> (k, m) [N].

    m = n: t = W^-1 w_req (the paper's eq. 6 solved directly; reported even
    outside the bounds), NaN where W is singular.  m > n: the minimum 2-norm
    tensions within the cable bounds, min 1/2 |t|^2 s.t. W t = w_req,
    t_min <= t <= t_max (:func:`cdpr_design.statics.tension.min_norm` pose by
    pose), NaN where the bounds admit none; ``lower`` (k, m) [N] the samples' lower bounds
    (default ``tension_min``; :func:`~cdpr_design.statics.robot.tension_lower`).  m < n: the least-squares
    solution where it balances w_req exactly, else NaN.
    """
    k, n, m = W.shape
    if m == n:
        return _square_tensions(W, wreq)
    if m > n:
        return _min_norm_tensions(W, wreq, np.broadcast_to(design.tension_min if lower is None else lower, (k, m)),
                                  design.tension_max)
    t = np.full((k, m), np.nan)
    for i in range(k):
        sol, *_ = np.linalg.lstsq(W[i], wreq[i], rcond=None)
        if np.linalg.norm(W[i] @ sol - wreq[i]) <= 1e-8 * (1 + np.linalg.norm(wreq[i])):
            t[i] = sol
    return t


def _square_tensions(W: np.ndarray, wreq: np.ndarray) -> np.ndarray:
    """t = W^-1 w_req for square W (k, n, n) [N], NaN where W is singular."""
    k, n, m = W.shape
    t = np.full((k, m), np.nan)
    det = np.linalg.det(W)
    scale = np.prod(np.linalg.norm(W, axis=2), axis=1)
    ok = np.abs(det) > 1e-10 * np.maximum(scale, 1e-300)
    if np.any(ok):
        t[ok] = np.linalg.solve(W[ok], wreq[ok][:, :, None])[:, :, 0]
    return t


def _min_norm_tensions(W: np.ndarray, wreq: np.ndarray, tmin, tmax) -> np.ndarray:
    """Bounded minimum 2-norm tensions (k, m) [N] of redundant robots, NaN where none exist;
    ``tmin`` (k, m) [N] each pose's lower bounds."""
    from cdpr_design.statics import tension  # imported here: it loads the numba kernels

    k, n, m = W.shape
    t = np.full((k, m), np.nan)
    for i in range(k):
        sol = tension.min_norm(W[i], wreq[i], np.ascontiguousarray(tmin[i]), tmax)
        if sol is not None:
            t[i] = sol
    return t


def states(robot: Robot, pose, velocity, acceleration, *, external=None) -> dict:
    """Cable lengths, speeds, accelerations and inertial tensions along a path.

    Parameters
    ----------
    robot : Robot
        The design resolved for ``motion`` (:func:`~cdpr_design.statics.robot.resolve`).
    pose, velocity, acceleration : (k, ncoords) arrays
        Pose [m, rad] and its time derivatives (angle rates for rotations).
    external : (n,) array, optional
        External wrench [N, N m], motion's rows.

    Returns
    -------
    dict with ``lengths``, ``cable_speed``, ``cable_accel``, ``tensions`` (k, m)
    and ``feasible`` (k,) of straight, ideal cables; ``structure`` (k, n, m),
    ``wrench`` (k, n) the wrench the cables exert [N, N m], ``positions``
    (k, 3) [m] and ``attachments`` (k, m, 3) the rotated attachments [m].

    Notes
    -----
    l_i = a_i - (p + R b_i) (paper eq. 1), L_i = |l_i|, u_i = l_i / L_i;
    with the attachment point's velocity v_B = v + w x R b_i and acceleration
    a_B = a + alpha x R b_i + w x (w x R b_i) (w and alpha exact from the rotation
    coordinates' derivatives, :func:`cdpr_design.statics.kinematics.euler_motion`):
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
    design = robot.design
    x, xd, xdd = (np.atleast_2d(np.asarray(a, float)) for a in (pose, velocity, acceleration))
    P, V, Acc = _full(design, x), _full(design, xd), _full(design, xdd)
    R, w, al = _body_rotation(design, P, V, Acc)
    Rb = np.einsum("kij,mj->kmi", R, design.attachments)  # (k, m, 3)
    vB = V[:, None, :3] + np.cross(w[:, None, :], Rb)
    aB = Acc[:, None, :3] + np.cross(al[:, None, :], Rb) + np.cross(w[:, None, :], np.cross(w[:, None, :], Rb))
    L, free, u, Ld, Ldd = _cable_motion(robot, P, Rb, vB, aB)
    W = _structure(design, u, Rb)
    wreq = -_load_wrenches(design, R, Acc, w, al, external)
    lower = tension_lower(robot.tension_min, robot.tension_floor, free)  # (k, m): the frequency floor
    t = solve_tensions(design, W, wreq, lower)
    t[degenerate(u)] = np.nan  # a cable of zero length: infeasible, as for `pose` (statics.degenerate)
    return {"lengths": L, "cable_speed": Ld, "cable_accel": Ldd, "tensions": t,
            "feasible": within_bounds(design, t, lower), "structure": W, "wrench": wreq, "positions": P[:, :3],
            "attachments": Rb}


def pose_at(samples: Samples, time) -> np.ndarray:
    """Linear interpolation of the sampled pose at given times [s] (clamped at the ends)."""
    time = np.asarray(time, float)
    return np.stack([np.interp(time, samples.time, samples.pose[:, j])
                     for j in range(samples.pose.shape[1])], axis=-1)


__all__ = [
    "DEFAULT_CYCLE_TIME", "Samples", "Segment", "TENSION_TOL", "motor_angles", "pose_at", "sample",
    "solve_tensions", "states", "within_bounds",
]
