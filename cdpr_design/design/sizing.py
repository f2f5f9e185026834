"""Motor, gearbox and drum sizing against a motor catalogue.

The seed paper's environment translates design inputs (workspace, motion and
load limits) into "the robot's structure, motors and sensors" (Rivera et al.,
Fig. 4); its planar prototype's tension limit 0 <= T <= 20 N came "from the
maximum torque of the motors".  This module makes that translation, per cable:

1. **Envelope over the task poses** (the grid over ``requirements.task_box``
   at the workspace's fixed orientation, or the statically feasible workspace
   grid when no task box is given):

   - static tension t0 (W t = w_req, w_req = -w_gravity);
   - dynamic tension when the platform accelerates with |a| <= A
     (``requirements.max_acceleration``): the inertial wrench is linear in a,
     w_req(a) = w0 + M a with M = [m I ; m [R c]x] (rows of the motion), so
     for m = n (t = W^-1 w unique) the worst case over the ball of
     accelerations is exact: t_i,max = t0_i + A ||row_i(W^-1 M)||;
     for m > n the minimum 2-norm tensions are evaluated at the vertices of a
     polytope inscribed in the ball (16 directions in the plane, 26 in space);
   - cable speed L'_i = -J_i v: the worst case over |v| <= V
     (``requirements.max_speed``) is V ||J_i,v|| = V (no angular velocity is
     required, so every attachment point moves with v);
   - cable acceleration L''_i = -u_i . a - |v_perp|^2 / L_i, bounded by
     A + V^2 / L_i over the task poses.

   With swivel pulleys (``cables[i].pulley``) lengths are arc + free
   segment and u_i leaves from the pulley's tangent point
   (:mod:`cdpr_design.statics.pulley`); L'_i = -u_i . v still holds (|u_i| = 1) and
   the curvature term is bounded by V^2 max(1 / l_f, |kappa_t|), the largest
   eigenvalue of the pulley-aware Hessian of L_i.

2. **Winch and motor** for a drum radius r, gear ratio i (motor turns per drum
   turn) and efficiency eta:

   - drum torque T r;
   - motor torque tau = T r / (i eta) + J_refl alpha, with the reflected
     inertia J_refl = J_rotor + J_gearbox + J_drum / i^2 and the motor's angular
     acceleration alpha = i a_cable / r (the peaks are added: a conservative
     sum-of-peaks sizing);
   - motor speed n = i v_cable / r  (x 60 / 2 pi for rpm);
   - RMS torque over a duty cycle: a sampled trajectory's (when given), or
     :data:`DEFAULT_CYCLE` otherwise.

3. **Choice**: the smallest catalogue motor whose usable peak torque, usable
   rated torque and speed limit cover the peak torque, RMS torque and peak
   speed times the safety factor; when ``winch.drum_radius`` or
   ``winch.gear_ratio`` list several values, every combination is searched.
   The inverse, the tension limit a motor implies, is
   t_max = tau_peak i eta / r (rated: tau_rated i eta / r).

The core never reads files: the catalogue arrives as a
:class:`~cdpr_design.model.catalogue.Catalogue` (read by
:func:`cdpr_design.model.spec.load_catalogue`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from cdpr_design.statics import kinematics as kin
from cdpr_design.errors import InputError
from cdpr_design.model.catalogue import Catalogue, Motor
from cdpr_design.model.design import Design, Grid

RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)

#: The default duty cycle used for the RMS torque when no trajectory is given:
#: at the cable's worst task pose, a trapezoidal move along the worst
#: acceleration direction -- accelerate at A up to V, cruise, decelerate at A,
#: dwell -- every phase lasting V / A seconds (four equal phases).  Tension
#: during the phases: t0 + A g (accelerate), t0 (cruise), t0 - A g (decelerate),
#: t0 (dwell, holding); cable acceleration +-A while accelerating/decelerating.
DEFAULT_CYCLE = ("accelerate", "cruise", "decelerate", "dwell")
DEFAULT_CYCLE_TEXT = ("default cycle at the worst task pose: accelerate at max_acceleration to "
                      "max_speed, cruise, decelerate, dwell; four phases of max_speed/max_acceleration each")


# ----------------------------------------------------------------------------
# Envelope of the task poses
# ----------------------------------------------------------------------------


def acceleration_directions(dim: int) -> np.ndarray:
    """Unit directions whose multiples by A are the vertices of the acceleration polytope.

    Planar: 16 evenly spaced directions; spatial: the 26 normalised vectors of
    {-1, 0, 1}^3 without 0 (cube vertices, edge and face centres).  The
    polytope is inscribed in the ball |a| <= A.
    """
    if dim == 2:
        ang = np.arange(16) * (2 * math.pi / 16)
        return np.stack([np.cos(ang), np.sin(ang)], axis=1)
    v = np.array([p for p in itertools.product((-1.0, 0.0, 1.0), repeat=3) if any(p)])
    return v / np.linalg.norm(v, axis=1, keepdims=True)


@dataclass
class Envelope:
    """Worst cases per cable over the task poses (arrays of length m).

    Attributes
    ----------
    poses : int
        Task poses evaluated.
    source : str
        ``task_box`` or ``feasible workspace``.
    static_tension : (m,) peak static tension [N].
    peak_tension : (m,) peak tension with the acceleration set [N].
    min_tension : (m,) least tension with the acceleration set [N] (below
        t_min means the cable would go slack at some acceleration).
    peak_cable_speed, peak_cable_accel : (m,) [m/s], [m/s^2].
    worst_pose : (m, ncoords) pose of each cable's peak tension.
    worst_static : (m,) static tension at that pose [N].
    worst_gain : (m,) (peak - static) / A at that pose [N per m/s^2]: the
        tension gained per unit of acceleration in the worst direction.
    singular : int
        Task poses where W is rank deficient (left out).
    """

    poses: int
    source: str
    static_tension: np.ndarray
    peak_tension: np.ndarray
    min_tension: np.ndarray
    peak_cable_speed: np.ndarray
    peak_cable_accel: np.ndarray
    worst_pose: np.ndarray
    worst_static: np.ndarray
    worst_gain: np.ndarray
    singular: int = 0
    max_speed: float = 0.0
    max_acceleration: float = 0.0


def task_grid(design: Design, step: float | None = None) -> Grid | None:
    """The grid over ``requirements.task_box`` (workspace step unless ``step`` [m]), or None."""
    box = design.requirements.task_box
    if box is None:
        return None
    st = (float(step),) * len(box[0]) if step is not None else design.workspace.grid.step
    return Grid(tuple(float(x) for x in box[0]), tuple(float(x) for x in box[1]), tuple(st))


def _structure_many(design: Design, positions: np.ndarray, Rb: np.ndarray, curvature: bool = False):
    """Structure matrices (k, n, m) and lengths (k, m) at positions (k, 3), fixed orientation.

    With swivel pulleys (:func:`cdpr_design.statics.kinematics.has_pulleys`) the
    lengths are arc + free segment and u_i the free segment's unit vector
    from the tangent point (:mod:`cdpr_design.statics.pulley`).  With ``curvature``
    a third array (k, m) [1/m] bounds the length's second derivative,
    |v^T H_i v| <= kappa_i |v|^2: 1 / L_i for a point outlet,
    max(1 / l_f, |kappa_t|) with a pulley (:meth:`CablePaths.max_curvature`).
    """
    if kin.has_pulleys(design):
        from cdpr_design.statics import pulley as pl

        paths = pl.design_cable_paths(design, positions[:, None, :] + Rb[None, :, :])
        L = paths.lengths
        u = paths.directions.copy()
        u[~(paths.free_lengths > 1e-12)] = 0.0
        kappa = paths.max_curvature()
    else:
        vec = design.outlets[None, :, :] - positions[:, None, :] - Rb[None, :, :]
        L = np.linalg.norm(vec, axis=2)
        with np.errstate(invalid="ignore", divide="ignore"):
            u = vec / L[:, :, None]
            kappa = 1.0 / L
        u[L <= 1e-12] = 0.0
    mom = np.cross(Rb[None, :, :], u)
    full = np.concatenate([u, mom], axis=2)  # (k, m, 6)
    W = np.transpose(full[:, :, list(design.motion.wrench_rows)], (0, 2, 1))
    if curvature:
        return np.ascontiguousarray(W), L, kappa
    return np.ascontiguousarray(W), L


def wrench_model(design: Design, orientation) -> tuple[np.ndarray, np.ndarray]:
    """w_req(a) = w0 + M a for a platform acceleration a (dim) at a fixed orientation.

    w0 = -w_gravity; M = rows of [m I ; m [R c]x] (d'Alembert: the cables must
    supply m a at the centre of mass besides balancing gravity).  Returns
    (w0 (n,), M (n, dim)).
    """
    d = design.motion.dim
    pose = np.zeros(len(design.motion.coords))
    pose[d:] = _rotation_coords(design, orientation)
    w0 = kin.required_wrench(design, pose)
    M = np.empty((design.n, d))
    for k in range(d):
        e = np.zeros(d)
        e[k] = 1.0
        # required wrench = -(gravity + inertial): the inertial part is linear in a
        M[:, k] = -kin.inertial_wrench(design, pose, e)
    return w0, M


def _rotation_coords(design: Design, ori3) -> np.ndarray:
    ori3 = np.asarray(ori3, float)
    name = design.motion.name
    if name == "1R2T":
        return ori3[2:3]
    if name == "3R3T":
        return ori3
    return np.zeros(0)


def _min_norm_general(W, wreq, tmin, tmax):
    """Minimum 2-norm tensions [N] for m > n at one pose, one row of ``wreq`` each.

    Bounded by [t_min, t_max] where that is feasible, otherwise by t_min only
    (the tension the winch must supply to hold the pose).  NaN where none.
    Exact: the Goldfarb-Idnani kernel through
    :func:`cdpr_design.statics.tension.min_norm_many` and
    :func:`~cdpr_design.statics.tension.min_norm_above` (imported here:
    they load numba, which the m = n designs never need).
    """
    from cdpr_design.statics import tension

    out = tension.min_norm_many(W, wreq, tmin, tmax)
    for k in np.flatnonzero(~np.all(np.isfinite(out), axis=1)):
        t = tension.min_norm_above(W, wreq[k], tmin, start=2.0 * float(np.max(tmax)))
        if t is not None:
            out[k] = t
    return out


def envelope_chunk(design: Design, positions: np.ndarray, orientation, A: float, V: float):
    """Per-pose worst cases for a chunk of positions (k, dim) at a fixed orientation.

    Returns a dict of (k, m) arrays: ``static``, ``peak``, ``low`` (least
    tension over the acceleration set), ``accel`` (cable acceleration bound),
    and a (k,) bool ``ok`` (W of full rank).
    """
    k = positions.shape[0]
    d = design.motion.dim
    m, n = design.m, design.n
    pos3 = np.zeros((k, 3))
    pos3[:, :d] = positions
    R = kin.rotation_matrix(*orientation)
    Rb = design.attachments @ R.T
    W, L, kappa = _structure_many(design, pos3, Rb, curvature=True)
    w0, M = wrench_model(design, orientation)
    static = np.full((k, m), np.nan)
    peak = np.full((k, m), np.nan)
    low = np.full((k, m), np.nan)
    ok = np.zeros(k, dtype=bool)
    if m == n:
        # t = W^-1 w is unique; the worst case over |a| <= A is t0 + A ||row_i(W^-1 M)||
        scale = np.abs(W).max(axis=(1, 2))
        det_ok = np.abs(np.linalg.det(W)) > 1e-10 * np.maximum(scale, 1e-300) ** n
        ok[:] = det_ok
        if det_ok.any():
            Wi = np.linalg.inv(W[det_ok])
            t0 = Wi @ w0
            G = np.linalg.norm(Wi @ M, axis=2)
            static[det_ok] = t0
            peak[det_ok] = t0 + A * G
            low[det_ok] = t0 - A * G
    else:
        dirs = acceleration_directions(d) * A
        wreq = np.vstack([w0[None, :], w0[None, :] + dirs @ M.T]) if A > 0 else w0[None, :]
        tmin, tmax = design.tension_min, design.tension_max
        for j in range(k):
            if np.linalg.matrix_rank(W[j]) < n:
                continue
            T = _min_norm_general(W[j], wreq, tmin, tmax)
            if not np.all(np.isfinite(T[0])):
                continue
            ok[j] = True
            static[j] = T[0]
            peak[j] = np.nanmax(T, axis=0)
            low[j] = np.nanmin(T, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        accel = A + V * V * kappa  # kappa = 1 / L for a point outlet
    accel[:, :] = np.where(L > 1e-12, accel, np.nan)
    return {"static": static, "peak": peak, "low": low, "accel": accel, "ok": ok}


def task_envelope(design: Design, *, step: float | None = None, positions: np.ndarray | None = None,
                  chunk: int = 4096, progress: Callable[[int, int], None] | None = None) -> Envelope:
    """Worst-case tensions, cable speeds and accelerations over the task poses.

    Parameters
    ----------
    design : Design
    step : float, optional
        Grid step [m] over the task box (default: ``workspace.grid.step``).
    positions : (k, dim) array, optional
        Evaluate these platform positions instead (at the workspace's fixed
        orientation).  Without a task box and without positions the statically
        feasible poses of the workspace grid are used.
    """
    from cdpr_design.workspace import engine as workspace  # core -> core (grid sweep driver)

    req = design.requirements
    A = float(req.max_acceleration or 0.0)
    V = float(req.max_speed or 0.0)
    ori = design.default_orientation_full()
    d = design.motion.dim
    if positions is not None:
        source = "given poses"
        blocks = [np.atleast_2d(np.asarray(positions, float))[:, :d]]
    elif req.task_box is not None:
        source = "task_box"
        g = task_grid(design, step)
        workspace.check_grid_size(g, False, "requirements.task_box")
        blocks = (workspace.grid_positions(g, s, min(chunk, g.size - s)) for s in range(0, g.size, chunk))
    else:
        source = "feasible workspace"
        feas: list[np.ndarray] = []
        workspace.run(design, "static", step=step, keep_maps=False,
                      on_chunk=lambda c: feas.append(c.poses[c.feasible.astype(bool), :d]))
        blocks = feas
    m = design.m
    ncoords = len(design.motion.coords)
    static = np.full(m, -np.inf)
    peak = np.full(m, -np.inf)
    low = np.full(m, np.inf)
    acc = np.full(m, -np.inf)
    worst_pose = np.full((m, ncoords), np.nan)
    worst_static = np.full(m, np.nan)
    worst_gain = np.full(m, np.nan)
    total = 0
    singular = 0
    rot = _rotation_coords(design, ori)
    for pos in blocks:
        if pos.shape[0] == 0:
            continue
        e = envelope_chunk(design, pos, ori, A, V)
        total += pos.shape[0]
        singular += int((~e["ok"]).sum())
        if not e["ok"].any():
            continue
        okp = e["ok"]
        static = np.fmax(static, np.nanmax(e["static"][okp], axis=0))
        low = np.fmin(low, np.nanmin(e["low"][okp], axis=0))
        acc = np.fmax(acc, np.nanmax(e["accel"][okp], axis=0))
        pk = np.where(okp[:, None], e["peak"], -np.inf)
        j = np.argmax(pk, axis=0)
        for i in range(m):
            if pk[j[i], i] > peak[i]:
                peak[i] = pk[j[i], i]
                worst_pose[i, :d] = pos[j[i]]
                worst_pose[i, d:] = rot
                worst_static[i] = e["static"][j[i], i]
                worst_gain[i] = (peak[i] - worst_static[i]) / A if A > 0 else 0.0
        if progress is not None:
            progress(total, total)
    for arr in (static, peak, acc):
        arr[~np.isfinite(arr)] = np.nan
    low[~np.isfinite(low)] = np.nan
    speed = np.full(m, V)  # |J_i v| <= V |u_i| = V for a translating platform
    return Envelope(total, source, static, peak, low, speed, acc, worst_pose, worst_static,
                    worst_gain, singular, V, A)


# ----------------------------------------------------------------------------
# Winch and motor
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class DutyCycle:
    """Per-cable load profile for the RMS torque: tension [N], cable acceleration [m/s^2], weights.

    ``tension`` and ``cable_accel`` are (k, m); ``weight`` (k,) sums to 1
    (time fraction of each sample).  ``cable_speed`` (k, m) [m/s] is used for
    the peak speed.  ``text`` says what the cycle is.
    """

    tension: np.ndarray
    cable_accel: np.ndarray
    cable_speed: np.ndarray
    weight: np.ndarray
    text: str


def default_cycle(env: Envelope) -> DutyCycle:
    """The :data:`DEFAULT_CYCLE` at each cable's worst task pose.

    Phases (equal durations V/A): accelerate (tension t0 + A g, cable
    reeled in at A), cruise (t0, speed V), decelerate (t0 - A g, -A), dwell
    (t0, holding).  Without an acceleration or speed requirement the cycle is
    pure holding at t0.
    """
    t0 = env.worst_static
    A = env.max_acceleration
    g = np.nan_to_num(env.worst_gain)
    V = env.max_speed
    if A > 0 and V > 0:
        ten = np.vstack([t0 + A * g, t0, t0 - A * g, t0])
        # reeling in is L'' < 0: the motor torque adds J alpha while it speeds the drum up
        acc = np.vstack([-np.full_like(t0, A), 0 * t0, np.full_like(t0, A), 0 * t0])
        spd = np.vstack([0 * t0, -np.full_like(t0, V), 0 * t0, 0 * t0])
        w = np.full(4, 0.25)
        return DutyCycle(ten, acc, spd, w, DEFAULT_CYCLE_TEXT)
    return DutyCycle(t0[None, :], 0 * t0[None, :], 0 * t0[None, :], np.ones(1),
                     "holding at the worst task pose (no max_speed/max_acceleration given)")


def trajectory_cycle(samples) -> DutyCycle:
    """Duty cycle of a sampled trajectory (``time``, ``tensions``, ``cable_speed``, ``cable_accel``)."""
    t = np.asarray(samples.time, float)
    if t.size > 1:
        dt = np.gradient(t)
        w = dt / dt.sum()
    else:
        w = np.ones(t.size)
    return DutyCycle(np.asarray(samples.tensions, float), np.asarray(samples.cable_accel, float),
                     np.asarray(samples.cable_speed, float), w,
                     f"trajectory {getattr(samples, 'name', '')}".strip())


@dataclass(frozen=True)
class WinchLoad:
    """What one cable asks of its winch for one drum radius / gear ratio / motor."""

    drum_radius: float
    gear_ratio: float
    efficiency: float
    gearbox: str
    reflected_inertia: float
    drum_torque: float
    peak_motor_torque: float
    rms_motor_torque: float
    peak_motor_speed: float


def motor_torque(tension, cable_accel, r, i, eta, J_refl):
    """Motor shaft torque [N m]: tau = T r / (i eta) - J_refl (i / r) L''.

    T [N] cable tension, L'' [m/s^2] cable length acceleration (negative while
    reeling in faster), r drum radius [m], i motor turns per drum turn, eta
    gearbox efficiency, J_refl = J_rotor + J_gearbox + J_drum / i^2 [kg m^2].
    """
    return np.asarray(tension) * r / (i * eta) - J_refl * (i / r) * np.asarray(cable_accel)


def reflected_inertia(rotor: float, gearbox: float, drum: float, i: float) -> float:
    """J_refl = J_rotor + J_gearbox + J_drum / i^2 [kg m^2] at the motor shaft."""
    return rotor + gearbox + drum / (i * i)


def winch_load(cable: int, env: Envelope, cycle: DutyCycle, r: float, i: float, eta: float,
               J_gear: float, J_drum: float, J_rotor: float, gearbox: str = "") -> WinchLoad:
    """Peak and RMS motor torque and peak speed of one cable for one winch choice."""
    J = reflected_inertia(J_rotor, J_gear, J_drum, i)
    T = env.peak_tension[cable]
    a = env.peak_cable_accel[cable]
    v = env.peak_cable_speed[cable]
    peak = T * r / (i * eta) + J * (i * a / r)
    tau = motor_torque(cycle.tension[:, cable], cycle.cable_accel[:, cable], r, i, eta, J)
    peak = max(peak, float(np.max(np.abs(tau))))
    rms = float(np.sqrt(np.sum(cycle.weight * tau * tau)))
    v = max(v, float(np.max(np.abs(cycle.cable_speed[:, cable]))))
    speed = i * v / r * RPM_PER_RAD_S
    return WinchLoad(r, i, eta, gearbox, J, T * r, float(peak), rms, float(speed))


def margins(load: WinchLoad, motor: Motor, sf: float) -> tuple[float, float, float]:
    """(peak torque, RMS torque, speed) margins: available / (safety factor x required)."""
    def ratio(avail, need):
        need = sf * need
        return math.inf if need <= 0 else avail / need
    return (ratio(motor.usable_peak_torque, load.peak_motor_torque),
            ratio(motor.usable_rated_torque, load.rms_motor_torque),
            ratio(motor.max_speed, load.peak_motor_speed))


@dataclass
class AxisSizing:
    """Sizing of one cable's axis (one row of ``motor_sizing.csv``)."""

    cable: str
    peak_tension: float
    peak_cable_speed: float
    drum_torque: float
    peak_motor_torque: float
    rms_motor_torque: float
    peak_motor_speed: float
    motor: str
    torque_margin: float
    speed_margin: float
    peak_torque_margin: float
    rms_torque_margin: float
    fits: bool
    evaluated_motor: str
    motor_from: str
    static_tension: float
    min_tension: float
    peak_cable_accel: float
    drum_radius: float
    gear_ratio: float
    efficiency: float
    gearbox: str
    reflected_inertia: float
    tension_min: float
    tension_max: float
    implied_tension_max: float
    implied_tension_rated: float
    usable_peak_torque: float
    usable_rated_torque: float
    motor_max_speed: float
    safety_factor: float

    CONTRACT = ("cable", "peak_tension", "peak_cable_speed", "drum_torque", "peak_motor_torque",
                "rms_motor_torque", "peak_motor_speed", "motor", "torque_margin", "speed_margin")

    def row(self) -> dict:
        """The contract columns in order, then the extras."""
        d = {k: getattr(self, k) for k in self.CONTRACT}
        for k, v in self.__dict__.items():
            if k not in d:
                d[k] = v
        return d


@dataclass
class SizingResult:
    """Motor sizing of every cable.

    ``axes`` one :class:`AxisSizing` per cable; ``envelope`` the worst cases;
    ``cycle`` what the RMS torque was computed over; ``ok`` every axis fits.
    """

    design_name: str
    axes: list[AxisSizing]
    envelope: Envelope
    cycle: str
    safety_factor: float
    notes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return all(a.fits for a in self.axes)

    def rows(self) -> list[dict]:
        return [a.row() for a in self.axes]

    def summary(self) -> dict:
        env = self.envelope
        return {
            "name": self.design_name, "ok": self.ok, "poses": env.poses, "pose_source": env.source,
            "singular_poses": env.singular, "cycle": self.cycle, "safety_factor": self.safety_factor,
            "max_speed": env.max_speed, "max_acceleration": env.max_acceleration,
            "notes": list(self.notes), "axes": [_jsonable(r) for r in self.rows()],
        }


def _jsonable(row: dict) -> dict:
    out = {}
    for k, v in row.items():
        if isinstance(v, (float, np.floating)):
            v = float(v)
            out[k] = v if math.isfinite(v) else None
        elif isinstance(v, np.bool_):
            out[k] = bool(v)
        else:
            out[k] = v
    return out


def _efficiency_given(design: Design, index: int) -> bool:
    """Whether the spec gives a winch efficiency for this cable (design-wide or per cable)."""
    raw = design.raw or {}
    w = raw.get("winch") or {}
    if isinstance(w, dict) and "efficiency" in w:
        return True
    cables = raw.get("cables") or []
    if index < len(cables) and isinstance(cables[index], dict):
        cw = cables[index].get("winch") or {}
        return isinstance(cw, dict) and "efficiency" in cw
    return False


def size_motors(design: Design, catalogue: Catalogue, *, step: float | None = None,
                samples=None, safety_factor: float | None = None, motor: str | None = None,
                envelope: Envelope | None = None,
                progress: Callable[[int, int], None] | None = None) -> SizingResult:
    """Size every cable's winch and motor.

    Parameters
    ----------
    design : Design
    catalogue : Catalogue
    step : float, optional
        Grid step [m] over the task box.
    samples : object with ``time, tensions, cable_speed, cable_accel``, optional
        A sampled trajectory (:func:`cdpr_design.motion.trajectory.sample`): its duty
        cycle gives the RMS torque, and its peaks join the envelope's.
    safety_factor : float, optional
        Factor >= 1 on the required torques and speed (default
        ``requirements.safety_factor``).
    motor : str, optional
        Evaluate this catalogue motor on every axis (instead of the spec's
        ``winch.motor`` or the smallest that fits).
    envelope : Envelope, optional
        Reuse a computed :func:`task_envelope`.

    Returns
    -------
    SizingResult

    Raises
    ------
    InputError
        A motor named by the spec or ``motor`` is not in the catalogue, or the
        safety factor is below 1.
    """
    sf = float(design.requirements.safety_factor if safety_factor is None else safety_factor)
    if not math.isfinite(sf) or sf < 1.0:
        raise InputError(f"--safety-factor: expected a number >= 1, got {sf}")
    if motor is not None and catalogue.motor(motor) is None:
        raise InputError(f"--motor: {motor!r} is not in the motor catalogue "
                         f"(known: {', '.join(m.name for m in catalogue.motors)})")
    for k, c in enumerate(design.cables):
        if motor is None and c.winch.motor is not None and catalogue.motor(c.winch.motor) is None:
            raise InputError(f"cables[{k}].winch.motor: {c.winch.motor!r} is not in the motor catalogue "
                             f"(known: {', '.join(m.name for m in catalogue.motors)}; add it with --catalogue FILE)")
    env = envelope if envelope is not None else task_envelope(design, step=step, progress=progress)
    notes = []
    if samples is not None:
        cycle = trajectory_cycle(samples)
        if getattr(samples, "feasible", None) is not None and not np.all(np.asarray(samples.feasible)):
            notes.append("the trajectory has infeasible samples")
    else:
        cycle = default_cycle(env)
    if env.singular:
        notes.append(f"{env.singular} task poses with a rank-deficient structure matrix were left out")
    by_size = catalogue.by_size()
    axes = []
    for k, c in enumerate(design.cables):
        w = c.winch
        named = motor if motor is not None else w.motor
        candidates = [catalogue.motor(named)] if named is not None else by_size
        best = None  # (key, load, motor, margins)
        for r, i in itertools.product(w.drum_radii, w.gear_ratios):
            gb = catalogue.gearbox(i)
            eta = w.efficiency if (_efficiency_given(design, k) or gb is None) else gb.efficiency
            J_gear = gb.inertia if gb is not None else 0.0
            for rank, mot in enumerate(candidates):
                load = winch_load(k, env, cycle, r, i, eta, J_gear, w.drum_inertia, mot.rotor_inertia,
                                  gb.name if gb is not None else "")
                mg = margins(load, mot, sf)
                fits = all(x >= 1.0 for x in mg)
                worst = min(mg)
                # prefer: fits, then the smallest motor, then the largest worst margin
                key = (0 if fits else 1, rank if fits else 0, -worst)
                if best is None or key < best[0]:
                    best = (key, load, mot, mg, fits)
                if fits and named is None:
                    break  # a larger motor on this winch cannot be smaller
        _, load, mot, mg, fits = best
        axes.append(AxisSizing(
            cable=c.name, peak_tension=float(env.peak_tension[k]),
            peak_cable_speed=float(max(env.peak_cable_speed[k], np.max(np.abs(cycle.cable_speed[:, k])))),
            drum_torque=load.drum_torque, peak_motor_torque=load.peak_motor_torque,
            rms_motor_torque=load.rms_motor_torque, peak_motor_speed=load.peak_motor_speed,
            motor=mot.name if fits or named is not None else "",
            torque_margin=min(mg[0], mg[1]), speed_margin=mg[2],
            peak_torque_margin=mg[0], rms_torque_margin=mg[1], fits=bool(fits),
            evaluated_motor=mot.name,
            motor_from="option" if motor is not None else ("spec" if w.motor is not None else "catalogue"),
            static_tension=float(env.static_tension[k]), min_tension=float(env.min_tension[k]),
            peak_cable_accel=float(env.peak_cable_accel[k]),
            drum_radius=load.drum_radius, gear_ratio=load.gear_ratio, efficiency=load.efficiency,
            gearbox=load.gearbox, reflected_inertia=load.reflected_inertia,
            tension_min=c.tension_min, tension_max=c.tension_max,
            implied_tension_max=implied_tension(mot.usable_peak_torque, load.drum_radius,
                                                load.gear_ratio, load.efficiency),
            implied_tension_rated=implied_tension(mot.usable_rated_torque, load.drum_radius,
                                                  load.gear_ratio, load.efficiency),
            usable_peak_torque=mot.usable_peak_torque, usable_rated_torque=mot.usable_rated_torque,
            motor_max_speed=mot.max_speed, safety_factor=sf,
        ))
    return SizingResult(design.name, axes, env, cycle.text, sf, notes)


def implied_tension(torque: float, drum_radius: float, gear_ratio: float = 1.0,
                    efficiency: float = 1.0) -> float:
    """Cable tension [N] a motor torque [N m] holds: t = tau i eta / r.

    The seed paper's limit 0 <= T <= 20 N came "from the maximum torque of
    the motors" (Rivera et al., section 3): this is that relation, inertia left out.
    """
    return torque * gear_ratio * efficiency / drum_radius


def drum_radius_for(tension: float, torque: float, gear_ratio: float = 1.0,
                    efficiency: float = 1.0) -> float:
    """The drum radius [m] at which ``torque`` [N m] holds ``tension`` [N]: r = tau i eta / t."""
    return torque * gear_ratio * efficiency / tension
