"""Time-optimal timing of a path: as fast as the robot allows, rest to rest on every segment.

Every segment of a path is a curve q(s) by its position s in [0, D] along it
(:class:`cdpr_design.motion.paths.Curve`) run from rest to rest: a straight segment (a square's
sides, a polyline's or csv path's legs, the approach from ``start``) q(s) = p0 + s e,
e = (p1 - p0) / D, its orientation (3R3T, 1R2T) interpolated with the position; a circle one curve
over all its laps, s the arc length.  With the path speed s' and acceleration u = s'' the pose
moves at q' s' and accelerates at q' u + q'' x, x = s'^2, and the angular velocity and
acceleration follow exactly from the rotation coordinates' derivatives
(:func:`cdpr_design.statics.kinematics.euler_motion`).  Along the curve the effector's dynamics are
therefore affine in u and x: the wrench the cables must supply is w = A(s) u + B(s) x + C(s) (A
from the mass matrix along q', B from q'' and the velocity terms of a rotating effector, the
centripetal and gyroscopic ones, C gravity), the cable accelerations L'' = L_s u + L_ss x and the
cable speeds L' = L_s s'.  The constraints, at every point of a grid along s:

- **tensions** within their bounds: w in the available wrench set, whose facets (hyperplane
  shifting, :mod:`cdpr_design.kernels.acceleration`) are linear inequalities in (u, x);
- **cable speeds** within each winch motor's speed (``winch.motor``'s ``max_speed`` through the
  drum radius and gear ratio): x <= (v_max / |L_s|)^2;
- **motor torques** within each motor's usable peak torque, tau = T r / (i eta) - J (i / r) L''
  (:func:`cdpr_design.design.winch.motor_torque`): with as many cables as wrench rows the
  tensions are affine in (u, x) and so is the torque, two inequalities a motor; with more cables
  the tensions are not unique and the motor's static part bounds the tension (T <= tau_peak i eta
  / r), the inertia's part checked on the samples afterwards (:attr:`Timing.torque_exceeded`);
- the path's own ``speed`` and ``acceleration`` (where the spec gives them) as upper limits on
  s' and |s''| (on an arc a/sqrt(2) for |s''| and for the centripetal x |q''|, so that the total
  stays within a, as the path's own profile keeps it).

A design without motor data is timed on the tensions (and the path's limits) alone, and says so
(:attr:`Timing.limits`).  The time-optimal (u, x) along s is found by reachability analysis
(TOPP-RA, Pham and Pham 2018; the ``toppra`` package) with these constraints given as its
canonical linear constraint, then sampled every cycle: each segment's time stretched to a whole
number of cycles by a uniform time scaling (speed / lambda, acceleration / lambda^2, lambda >= 1),
which keeps (u, x) inside the convex feasible set that holds rest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from cdpr_design.design.winch import RPM_PER_RAD_S, reflected_inertia
from cdpr_design.model.design import Design, Trajectory
from cdpr_design.motion import paths
from cdpr_design.motion import trajectory as tr
from cdpr_design.statics.robot import Robot, tension_lower

#: Grid points of a segment: one every GRID_STEP [m] of path (rad for a pure rotation), at least
#: GRID_MIN and at most GRID_MAX.
GRID_STEP, GRID_MIN, GRID_MAX = 5e-4, 100, 4000
#: Relative share of each tension range kept free of the constraint [-]: the grid's constraints
#: hold at its points, the samples fall between them.
TENSION_GUARD = 1e-4
#: A constraint is *active* at a grid point when its slack is within this share of its scale.
ACTIVE_TOL = 1e-3
#: The names of the constraints (``Timing.active``).
CONSTRAINTS = ("tension", "motor_torque", "cable_speed", "path_speed", "path_acceleration")
#: Upper bound standing for "no limit" in the solver's bounds.
_UNBOUNDED = 1e12


@dataclass(frozen=True)
class WinchLimits:
    """What the winches allow, per cable (m,): ``speed`` cable speed [m/s] (inf: no motor),
    ``torque`` usable peak torque [N m] (inf: none), ``rho`` = r / (i eta) [m], ``kappa`` = J_refl
    i / r [kg m] (tau = rho T - kappa L''), ``motors`` whether any cable has motor data."""

    speed: np.ndarray
    torque: np.ndarray
    rho: np.ndarray
    kappa: np.ndarray
    motors: bool


def winch_limits(design: Design, catalogue=None) -> WinchLimits:
    """The :class:`WinchLimits` of ``design``'s winches, motors looked up in ``catalogue`` (default
    the shipped one); a cable whose winch names no motor (or one not in the catalogue) is unlimited."""
    from cdpr_design.model import spec

    cat = catalogue if catalogue is not None else spec.load_catalogue()
    m = design.m
    speed, torque = np.full(m, np.inf), np.full(m, np.inf)
    rho, kappa = np.zeros(m), np.zeros(m)
    any_motor = False
    for k, c in enumerate(design.cables):
        w = c.winch
        r, i, eta = w.drum_radius, w.gear_ratio, w.efficiency
        rho[k] = r / (i * eta)
        motor = cat.motor(w.motor) if w.motor else None
        if motor is None:
            continue
        any_motor = True
        speed[k] = motor.max_speed / RPM_PER_RAD_S * r / i
        torque[k] = motor.usable_peak_torque
        kappa[k] = reflected_inertia(motor.rotor_inertia, 0.0, w.drum_inertia, i) * i / r
    return WinchLimits(speed, torque, rho, kappa, any_motor)


@dataclass
class SegmentTiming:
    """One segment's time-optimal profile: ``s`` (N+1,) grid [m or rad], ``speed`` (N+1,) s' [m/s],
    ``limit`` (N+1,) the largest s' the constraints allow at each point (the maximum velocity
    curve) [m/s], ``active`` (N+1,) the index in :data:`CONSTRAINTS` of the constraint active at
    each point (-1: none), ``duration`` [s] as sampled (whole cycles), ``start`` [m] where it
    starts along the whole path, ``stoppable`` and ``reachable`` (N+1,) [m/s] the largest s' from
    which the end is still reached at rest, and reached from rest at the start (the reachability
    analysis' sets; the profile is the least of the two)."""

    s: np.ndarray
    speed: np.ndarray
    limit: np.ndarray
    active: np.ndarray
    duration: float
    start: float = 0.0
    stoppable: np.ndarray | None = None
    reachable: np.ndarray | None = None


@dataclass
class Timing:
    """What :func:`sample` found besides the samples: ``segments`` (one :class:`SegmentTiming` a
    timed segment), ``profiled_duration`` [s] the duration of the path's own profile (None when the
    path gives no speed and acceleration), ``limits`` the constraints applied, ``note`` a sentence
    for a design timed on its tensions alone (None otherwise), ``torque_exceeded`` the samples whose
    motor torque (the inverse dynamics' tensions and the winch inertia) exceeds a motor's peak."""

    segments: list = field(default_factory=list)
    profiled_duration: float | None = None
    limits: tuple = ()
    note: str | None = None
    torque_exceeded: int = 0

    def active_shares(self) -> dict:
        """The share of the grid points (all segments) at which each constraint is active, and
        ``none`` (JSON-ready)."""
        act = np.concatenate([g.active for g in self.segments]) if self.segments else np.zeros(0, int)
        n = max(act.size, 1)
        out = {name: float(np.count_nonzero(act == k)) / n for k, name in enumerate(CONSTRAINTS)}
        out["none"] = float(np.count_nonzero(act < 0)) / n
        return out

    def active_intervals(self) -> list[dict]:
        """Where each constraint is active: runs of grid points, as ``{segment, from, to, constraint}``
        with the path positions [m] along the whole path."""
        out = []
        for k, g in enumerate(self.segments):
            a = g.active
            start = 0
            for j in range(1, a.size + 1):
                if j == a.size or a[j] != a[start]:
                    if a[start] >= 0:
                        out.append({"segment": k, "from": float(g.start + g.s[start]),
                                    "to": float(g.start + g.s[j - 1]), "constraint": CONSTRAINTS[a[start]]})
                    start = j
        return out

    def summary(self) -> dict:
        """The ``trajectory.json`` keys of a time-optimal timing (JSON-ready)."""
        return {"profiled_duration": self.profiled_duration, "limits": list(self.limits), "limits_note": self.note,
                "active": self.active_shares(), "active_intervals": self.active_intervals(),
                "torque_exceeded_samples": self.torque_exceeded}


class PathConstraint:
    """The constraints of one segment at its grid points, as toppra's canonical linear constraint:
    rows a u + b x + c <= 0 (``a``, ``b``, ``c`` (N+1, k)), bounds on u and x (N+1, 2), and the
    constraint each row belongs to (``kinds`` (k,), indices in :data:`CONSTRAINTS`)."""

    def __init__(self, a, b, c, ubound, xbound, kinds, xkinds):
        self.a, self.b, self.c, self.ubound, self.xbound = a, b, c, ubound, xbound
        self.kinds, self.xkinds = kinds, xkinds

    def toppra(self):
        """This constraint as a ``toppra.constraint.LinearConstraint`` (its documented extension point),
        discretised by interpolation: each interval's (u_i, x) is held to the rows at both its ends
        (x_i at its start, x_i + 2 ds u_i at its end), so that the samples between two grid
        points keep the constraints but for the rows' own change along the interval."""
        import toppra.constraint as tc

        rows = self

        class _Linear(tc.LinearConstraint):
            def __init__(self):
                super().__init__()
                self.identical = True  # F v <= g with one F and g: v = a u + b x + c, F = I, g = 0
                self.set_discretization_type(tc.DiscretizationType.Interpolation)

            def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
                k = rows.a.shape[1]
                a, b, c, F, g, _, _ = tc.canlinear_colloc_to_interpolate(
                    rows.a, rows.b, rows.c, np.eye(k), np.zeros(k), None, None, np.asarray(gridpoints),
                    identical=True)
                return a, b, c, F, g, rows.ubound, rows.xbound

        return _Linear()


def _segment_constraint(robot: Robot, curve: paths.Curve, s, limits: WinchLimits, speed: float | None,
                        accel: float | None) -> tuple[PathConstraint, np.ndarray]:
    """The :class:`PathConstraint` of the path ``curve`` at the grid ``s`` (N+1,), and each point's
    static slack (N+1,) [N] (negative: the pose is not held at rest).  ``accel`` [m/s^2]: the path's
    tangential acceleration limit (:func:`_path_accelerations`)."""
    from cdpr_design.kernels import acceleration as KA  # numba, on first use

    k = s.size
    q, dq, ddq = curve.at(s)
    zero = np.zeros_like(q)
    rest = tr.states(robot, q, zero, zero)
    push = tr.states(robot, q, zero, dq)  # u = 1: q'' = q'(s)
    move = tr.states(robot, q, dq, ddq)  # x = 1 (s' = 1): q' = q'(s), q'' = q''(s)
    W = rest["structure"]
    C = rest["wrench"]
    A = push["wrench"] - C
    B = move["wrench"] - C
    Ls = push["cable_accel"]  # dL/ds: L'' at u = 1, x = 0
    Lss = move["cable_accel"]  # d2L/ds2: L'' at u = 0, x = 1
    lo = tension_lower(robot.tension_min, robot.tension_floor, rest["lengths"])
    hi = np.broadcast_to(robot.tension_max, lo.shape).copy()
    square = robot.m == robot.n
    if not square:  # the motors' static part bounds the tensions (module doc)
        hi = np.minimum(hi, np.where(np.isfinite(limits.torque), limits.torque / limits.rho, np.inf)[None, :])
    guard = np.where(np.isfinite(hi - lo), TENSION_GUARD * (hi - lo), 0.0)
    rows_a, rows_b, rows_c, kinds = [], [], [], []
    # tensions: the facets of the available wrench set, n_f . w <= b+ and -n_f . w <= -b-
    nf = robot.combos.shape[0]
    normals, bp, bm = np.empty((k, nf, robot.n)), np.empty((k, nf)), np.empty((k, nf))
    KA.facets_many(np.ascontiguousarray(W), np.ascontiguousarray(lo + guard), np.ascontiguousarray(hi - guard),
                   robot.combos, normals, bp, bm)
    for sign, bound in ((1.0, bp), (-1.0, bm)):
        rows_a.append(sign * np.einsum("kfn,kn->kf", normals, A))
        rows_b.append(sign * np.einsum("kfn,kn->kf", normals, B))
        rows_c.append(sign * (np.einsum("kfn,kn->kf", normals, C) - bound))
        kinds += [0] * nf
    static = -np.nanmax(np.concatenate(rows_c, axis=1), axis=1)
    # motor torques (as many cables as wrench rows: tensions affine in u and x)
    motors = np.isfinite(limits.torque)
    if square and motors.any():
        Winv = np.linalg.inv(W)
        ta, tb, tc = (np.einsum("kij,kj->ki", Winv, v) for v in (A, B, C))
        rho, kap, tau = limits.rho, limits.kappa, limits.torque
        for sign in (1.0, -1.0):
            rows_a.append((sign * (rho * ta - kap * Ls))[:, motors])
            rows_b.append((sign * (rho * tb - kap * Lss))[:, motors])
            rows_c.append((sign * rho * tc - tau)[:, motors])
            kinds += [1] * int(motors.sum())
    a = np.nan_to_num(np.concatenate(rows_a, axis=1))
    b = np.nan_to_num(np.concatenate(rows_b, axis=1))
    c = np.nan_to_num(np.concatenate(rows_c, axis=1))
    # the path speed and the cable speeds bound x = s'^2; the path's acceleration bounds u
    xmax = np.full(k, _UNBOUNDED)
    xkind = np.full(k, -1)
    if speed is not None:
        xmax[:] = speed * speed
        xkind[:] = 3
    with np.errstate(divide="ignore", invalid="ignore"):
        cable_x = np.where(np.abs(Ls) > 0, (limits.speed[None, :] / np.abs(Ls)) ** 2, np.inf).min(axis=1)
    lower_cable = cable_x < xmax
    xmax[lower_cable] = cable_x[lower_cable]
    xkind[lower_cable] = 2
    if accel is not None and curve.curved:  # the centripetal acceleration x |q''| within the path's limit
        kappa = np.linalg.norm(ddq[:, :robot.design.motion.dim], axis=1)
        with np.errstate(divide="ignore"):
            turn_x = np.where(kappa > 0, accel / kappa, np.inf)
        lower_turn = turn_x < xmax
        xmax[lower_turn] = turn_x[lower_turn]
        xkind[lower_turn] = 4
    ub = _UNBOUNDED if accel is None else float(accel)
    ubound = np.tile([-ub, ub], (k, 1))
    xbound = np.column_stack([np.zeros(k), xmax])
    return PathConstraint(a, b, c, ubound, xbound, np.array(kinds), xkind), static


def _active(pc: PathConstraint, u, x, accel: float | None) -> np.ndarray:
    """The constraint active at each grid point (index in :data:`CONSTRAINTS`, -1 none): the row of
    least slack, relative to its scale, when within :data:`ACTIVE_TOL`, with the path acceleration
    of either interval the point ends or starts (``u`` (N,), ``x`` (N+1,))."""
    k = x.size
    if u.size == 0:
        return np.full(k, -1)
    best, kind = np.full(k, np.inf), np.full(k, -1)
    after, before = np.append(u, u[-1]), np.concatenate([u[:1], u])
    for uu in (after, before):
        rows = pc.a * uu[:, None] + pc.b * x[:, None] + pc.c
        scale = np.abs(pc.a * uu[:, None]) + np.abs(pc.b * x[:, None]) + np.abs(pc.c) + 1e-12
        rel = -rows / scale
        if rel.shape[1]:
            i = np.argmin(rel, axis=1)
            r = rel[np.arange(k), i]
            better = r < best
            best[better], kind[better] = r[better], pc.kinds[i[better]]
    xs = (pc.xbound[:, 1] - x) / np.maximum(pc.xbound[:, 1], 1e-12)
    better = (pc.xkinds >= 0) & (xs < best)
    best[better], kind[better] = xs[better], pc.xkinds[better]
    if accel is not None:
        us = (accel - np.maximum(np.abs(after), np.abs(before))) / accel
        better = us < best
        best[better], kind[better] = us[better], 4
    return np.where(best <= ACTIVE_TOL, kind, -1)


def _path_accelerations(curve: paths.Curve, accel: float | None) -> float | None:
    """The limit [m/s^2] of the path acceleration s'' (and of a curve's centripetal acceleration
    s'^2 |q''|) from the path's ``acceleration``: all of it along a straight segment, 1/sqrt(2) of
    it on an arc, so that the total never exceeds it (as the path's own profile,
    :func:`cdpr_design.motion.paths.circle_samples`)."""
    if accel is None:
        return None
    return float(accel) / math.sqrt(2.0) if curve.curved else float(accel)


def time_segment(robot: Robot, curve: paths.Curve | None, dt: float, limits: WinchLimits, speed: float | None,
                 accel: float | None, where: str):
    """The time-optimal samples of the path ``curve`` (a straight segment or a whole circle, rest to
    rest, its start excluded) every ``dt`` [s]: ((pose, velocity, acceleration) (N, ncoords) arrays,
    :class:`SegmentTiming`), or None for a segment of zero length (``curve`` None).  ``speed``
    [m/s] and ``accel`` [m/s^2]: the path's own limits (None: none); ``where`` names the segment
    in the errors.

    Raises
    ------
    ValueError
        A grid point of the path is not held at rest (the message names the first), or the
        solver finds no profile.
    """
    import toppra

    if curve is None:
        return None
    D = curve.length
    a_t = _path_accelerations(curve, accel)
    n = int(min(GRID_MAX, max(GRID_MIN, math.ceil(D / GRID_STEP))))
    s = np.linspace(0.0, D, n + 1)
    pc, static = _segment_constraint(robot, curve, s, limits, speed, a_t)
    bad = np.flatnonzero(~(static >= 0.0))
    if bad.size:
        j = int(bad[0])
        pose = curve.at(s[j:j + 1])[0][0]
        raise ValueError(f"{where}: the path is not statically feasible at s = {s[j]:.6g} along it, pose "
                         f"({', '.join(f'{v:.6g}' for v in pose)}): no tensions within the bounds hold the effector "
                         "at rest there, so the path cannot be timed")
    path = toppra.SplineInterpolator([0.0, D], np.array([[0.0], [D]]), bc_type="natural")
    algo = toppra.algorithm.TOPPRA([pc.toppra()], path, gridpoints=s, parametrizer="ParametrizeConstAccel")
    sdd, sd, _ = algo.compute_parameterization(0.0, 0.0)
    if sd is None:
        raise ValueError(f"{where}: no profile from rest to rest satisfies the constraints")
    x = np.maximum(np.asarray(sd, float), 0.0) ** 2
    sd = np.sqrt(x)
    u = np.asarray(sdd, float)
    feasible = algo.compute_feasible_sets()
    limit = np.sqrt(np.maximum(np.nan_to_num(feasible[:, 1]), 0.0))
    stoppable = np.sqrt(np.maximum(np.nan_to_num(algo.compute_controllable_sets(0.0, 0.0)[:, 1]), 0.0))
    reachable = np.sqrt(np.maximum(np.nan_to_num(algo.compute_reachable_sets(0.0, 0.0)[:, 1]), 0.0))
    active = _active(pc, u, x, a_t)
    # time of each interval at constant s'' (the parameterisation's own interpolation)
    ds = np.diff(s)
    with np.errstate(divide="ignore", invalid="ignore"):
        dti = np.where(sd[:-1] + sd[1:] > 0, 2.0 * ds / (sd[:-1] + sd[1:]), 0.0)
    t_grid = np.concatenate([[0.0], np.cumsum(dti)])
    T = float(t_grid[-1])
    cycles = max(1, math.ceil(T / dt - 1e-9))
    lam = cycles * dt / T  # >= 1: slower, so still within the (convex) constraints
    t = np.arange(1, cycles + 1) * dt / lam
    i = np.clip(np.searchsorted(t_grid, t, side="right") - 1, 0, n - 1)
    tau = t - t_grid[i]
    sdd_i = np.where(dti[i] > 0, (sd[i + 1] - sd[i]) / np.where(dti[i] > 0, dti[i], 1.0), 0.0)
    pos = np.minimum(s[i] + sd[i] * tau + 0.5 * sdd_i * tau * tau, D)
    vel = np.maximum(sd[i] + sdd_i * tau, 0.0) / lam
    acc = sdd_i / (lam * lam)
    pos[-1], vel[-1] = D, 0.0
    pose, velocity, acceleration = curve.motion(pos, vel, acc)
    pose[-1] = curve.end
    timing = SegmentTiming(s, sd / lam, limit, active, cycles * dt, stoppable=stoppable, reachable=reachable)
    return (pose, velocity, acceleration), timing


def sample(robot: Robot, trajectory: str | Trajectory, cycle_time: float | None = None, *,
           csv_poses=None, hold_end: float = 0.0, catalogue=None) -> tuple:
    """The spec trajectory timed as fast as the robot allows (see the module doc), sampled every
    ``cycle_time`` [s] (default the trajectory's, else 1 ms) as :func:`cdpr_design.motion.trajectory.sample`
    samples its profile.  Returns (:class:`~cdpr_design.motion.trajectory.Samples`, :class:`Timing`).

    ``robot``: the design resolved for ``motion`` with ``time_optimal``
    (``resolve(design, Analysis(command="motion", time_optimal=True))``: sagging cables are refused there).

    Raises
    ------
    KeyError
        Unknown trajectory name.
    ValueError
        A pose of the path not held at rest (the message names the first), no profile found, or
        bad poses.
    """
    design = robot.design
    traj = trajectory if not isinstance(trajectory, str) else design.trajectories.get(trajectory)
    if traj is None:
        raise KeyError(f"no trajectory named {trajectory!r}")
    limits = winch_limits(design, catalogue)
    timing = Timing()
    timing.limits = tuple(n for n, on in (("tension", True), ("motor_torque", limits.motors),
                                          ("cable_speed", limits.motors), ("path_speed", traj.speed is not None),
                                          ("path_acceleration", traj.acceleration is not None)) if on)
    if not limits.motors:
        timing.note = "no winch motor in the spec (winch.motor): timed on the tensions alone"
    done = [0.0]

    def timed(curve, dt):
        where = f"trajectories.{traj.name}: segment {len(timing.segments) + 1}"
        got = time_segment(robot, curve, dt, limits, traj.speed, traj.acceleration, where)
        if got is None:
            return None
        block, seg = got
        seg.start = done[0]
        done[0] += float(seg.s[-1])
        timing.segments.append(seg)
        return block

    def line(_design, _traj, p0, p1, dt):
        return timed(paths.line_curve(design, p0, p1), dt)

    def arc(_design, _traj, dt):
        return timed(paths.circle_curve(design, traj), dt)

    samples = tr.sample(robot, traj, cycle_time, csv_poses=csv_poses, hold_end=hold_end, line=line, arc=arc)
    if traj.speed is not None and traj.acceleration is not None:
        timing.profiled_duration = tr.sample(robot, traj, cycle_time, csv_poses=csv_poses,
                                             hold_end=hold_end).duration
    timing.torque_exceeded = torque_exceeded(samples, limits)
    return samples, timing


def torque_exceeded(samples, limits: WinchLimits) -> int:
    """How many samples ask a motor for more than its usable peak torque [N m] (the samples'
    tensions and cable accelerations through :func:`cdpr_design.design.winch.motor_torque`'s formula)."""
    if not np.isfinite(limits.torque).any():
        return 0
    tau = samples.tensions * limits.rho[None, :] - limits.kappa[None, :] * samples.cable_accel
    with np.errstate(invalid="ignore"):
        over = np.abs(tau) > limits.torque[None, :] * (1 + 1e-9)
    return int(np.count_nonzero(over.any(axis=1)))
