"""Motor, gearbox and drum sizing against a motor catalogue.

The seed paper's environment translates design inputs (workspace, motion and
load limits) into "the robot's structure, motors and sensors" (Rivera et al.,
Fig. 4); its planar prototype's tension limit 0 <= T <= 20 N came "from the
maximum torque of the motors".  :func:`size_motors` makes that translation,
per cable:

1. **Envelope over the task poses** (:mod:`cdpr_design.design.envelope`):
   peak static and dynamic tension, cable speed and acceleration.
2. **Winch and motor** (:mod:`cdpr_design.design.winch`): peak and RMS motor
   torque and motor speed for a drum radius, gear ratio and efficiency, the
   RMS over a duty cycle (:mod:`cdpr_design.design.duty`).
3. **Choice**: the smallest catalogue motor whose usable peak torque, usable
   rated torque and speed limit cover the peak torque, RMS torque and peak
   speed times the safety factor; when ``winch.drum_radius`` or
   ``winch.gear_ratio`` list several values, every combination is searched.

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

from cdpr_design.design.duty import DutyCycle, default_cycle, trajectory_cycle
from cdpr_design.design.envelope import Envelope, task_envelope
from cdpr_design.design.winch import WinchLoad, implied_tension, margins, winch_load
from cdpr_design.errors import InputError, quote
from cdpr_design.io.tables import Table, rows_to_columns
from cdpr_design.model.catalogue import Catalogue, Motor
from cdpr_design.model.design import Cable, Design
from cdpr_design.statics.robot import Robot


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
class SizingResult(Table):
    """Motor sizing of every cable.

    ``axes`` one :class:`AxisSizing` per cable; ``envelope`` the worst cases;
    ``cycle`` what the RMS torque was computed over; ``ok`` every axis fits.
    As a table: the ``motor_sizing.csv`` columns, one row per cable.
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

    def columns(self) -> dict:
        """The ``motor_sizing.csv`` columns (name -> list, one value per cable)."""
        return rows_to_columns(self.rows())

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


def size_motors(robot: Robot, catalogue: Catalogue, *, step: float | None = None,
                samples=None, safety_factor: float | None = None, motor: str | None = None,
                envelope: Envelope | None = None,
                progress: Callable[[int, int], None] | None = None, engine: str = "auto") -> SizingResult:
    """Size every cable's winch and motor.

    Parameters
    ----------
    robot : Robot
        The design resolved for ``size-motors`` (:func:`~cdpr_design.statics.robot.resolve`).
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
        Reuse a computed :func:`~cdpr_design.design.envelope.task_envelope`.
    progress : callable(done, total), optional
        Called as the task poses are evaluated.
    engine : {'auto', 'numba', 'numpy'}
        Engine of the workspace sweep behind the envelope (no task box).

    Returns
    -------
    SizingResult

    Raises
    ------
    InputError
        A motor named by the spec or ``motor`` is not in the catalogue, or the
        safety factor is below 1.
    """
    design = robot.design
    sf = check_options(design, catalogue, safety_factor, motor)
    env = envelope if envelope is not None else task_envelope(robot, step=step, progress=progress, engine=engine)
    notes = []
    if samples is not None:
        cycle = trajectory_cycle(samples)
        if getattr(samples, "feasible", None) is not None and not np.all(np.asarray(samples.feasible)):
            notes.append("the trajectory has infeasible samples")
    else:
        cycle = default_cycle(env)
    if env.singular:
        notes.append(f"{env.singular} task poses with a rank-deficient structure matrix or a cable of zero length were left out")
    by_size = catalogue.by_size()
    axes = []
    for k, c in enumerate(design.cables):
        named = motor if motor is not None else c.winch.motor
        candidates = [catalogue.motor(named)] if named is not None else by_size
        choice = _choose(design, k, env, cycle, catalogue, candidates, sf, smallest=named is None)
        source = "option" if motor is not None else ("spec" if c.winch.motor is not None else "catalogue")
        axes.append(_axis(c, k, env, cycle, choice, source, sf))
    return SizingResult(design.name, axes, env, cycle.text, sf, notes)


def check_options(design: Design, catalogue: Catalogue, safety_factor: float | None = None,
                  motor: str | None = None) -> float:
    """Check the sizing options before any work (a job calls it before writing a file): the
    safety factor (>= 1, default ``requirements.safety_factor``), returned, and every motor name."""
    sf = float(design.requirements.safety_factor if safety_factor is None else safety_factor)
    if not math.isfinite(sf) or sf < 1.0:
        raise InputError(f"--safety-factor: expected a number >= 1, got {sf}")
    _check_motor_names(design, catalogue, motor)
    return sf


def _check_motor_names(design: Design, catalogue: Catalogue, motor: str | None) -> None:
    """InputError when ``motor`` (or, without it, a spec's ``winch.motor``) is not in the catalogue."""
    known = ", ".join(m.name for m in catalogue.motors)
    if motor is not None and catalogue.motor(motor) is None:
        raise InputError(f"--motor: {quote(motor)} is not in the motor catalogue (known: {known})")
    for k, c in enumerate(design.cables):
        if motor is None and c.winch.motor is not None and catalogue.motor(c.winch.motor) is None:
            raise InputError(f"cables[{k}].winch.motor: {quote(c.winch.motor)} is not in the motor catalogue "
                             f"(known: {known}; add it with --catalogue FILE)")


@dataclass(frozen=True)
class _Choice:
    """One cable's chosen winch and motor: its load, the motor, (peak, RMS, speed) margins, whether it fits."""

    load: WinchLoad
    motor: Motor
    margins: tuple[float, float, float]
    fits: bool


def _choose(design: Design, k: int, env: Envelope, cycle: DutyCycle, catalogue: Catalogue,
            candidates: list[Motor], sf: float, smallest: bool) -> _Choice:
    """The best (drum radius, gear ratio, motor) of cable k.

    Prefer a fit, then the smallest motor (``candidates`` from the smallest;
    with ``smallest`` the search of a winch stops at its first fit), then the
    largest worst margin.
    """
    w = design.cables[k].winch
    best, best_key = None, None
    for r, i in itertools.product(w.drum_radii, w.gear_ratios):
        gb = catalogue.gearbox(i)
        eta = w.efficiency if (_efficiency_given(design, k) or gb is None) else gb.efficiency
        J_gear = gb.inertia if gb is not None else 0.0
        for rank, mot in enumerate(candidates):
            load = winch_load(k, env, cycle, r, i, eta, J_gear, w.drum_inertia, mot.rotor_inertia,
                              gb.name if gb is not None else "")
            mg = margins(load, mot, sf)
            fits = all(x >= 1.0 for x in mg)
            key = (0 if fits else 1, rank if fits else 0, -min(mg))
            if best_key is None or key < best_key:
                best, best_key = _Choice(load, mot, mg, fits), key
            if fits and smallest:
                break  # a larger motor on this winch cannot be smaller
    return best


def _axis(c: Cable, k: int, env: Envelope, cycle: DutyCycle, choice: _Choice, motor_from: str,
          sf: float) -> AxisSizing:
    """The ``motor_sizing.csv`` row of cable k (index ``k``) for its chosen winch and motor."""
    load, mot, mg, fits = choice.load, choice.motor, choice.margins, choice.fits
    return AxisSizing(
        cable=c.name, peak_tension=float(env.peak_tension[k]),
        peak_cable_speed=float(max(env.peak_cable_speed[k], np.max(np.abs(cycle.cable_speed[:, k])))),
        drum_torque=load.drum_torque, peak_motor_torque=load.peak_motor_torque,
        rms_motor_torque=load.rms_motor_torque, peak_motor_speed=load.peak_motor_speed,
        motor=mot.name if fits or motor_from != "catalogue" else "",
        torque_margin=min(mg[0], mg[1]), speed_margin=mg[2],
        peak_torque_margin=mg[0], rms_torque_margin=mg[1], fits=bool(fits),
        evaluated_motor=mot.name, motor_from=motor_from,
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
    )
