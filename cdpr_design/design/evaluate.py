"""Headline figures and requirement checks of one design (the ``design_report.csv`` row).

:func:`evaluate` is a pure function of the design (and the catalogue): it
sweeps the workspace, sweeps the task box, sizes the motors and tests the
``requirements:`` section, and returns one flat dict of plain Python values
(str, int, float, bool, None), picklable, ready to be a CSV row.  ``report``,
``check`` and the batch ``sweep`` all use it.

Checks (``check_<name>``: True pass, False fail, None not asked for):

- ``task_box``: every grid pose of ``requirements.task_box`` is feasible
  (``wrench-feasible`` when the spec gives ``workspace.external_wrench``,
  otherwise ``static``);
- ``min_margin``: the least capacity margin over the task box (over the
  feasible workspace when there is no task box) is at least
  ``requirements.min_margin``; an infeasible task pose has a negative margin
  or none (rank deficient, or a hanging effector rejected for its tilt or its
  hanging tensions), and one without fails;
- ``min_fraction``: the feasible fraction of the workspace grid is at least
  ``requirements.min_fraction``;
- ``motors``: every axis's motor covers peak torque, RMS torque and speed with
  the safety factor.  Asked for when the spec names a motor or gives
  ``max_speed`` / ``max_acceleration``;
- ``max_frame_load`` (only when the spec asks): the largest force a cable puts on the frame at its
  outlet over the feasible workspace grid, with the sweep's tensions
  (:mod:`cdpr_design.workspaces.frame_loads`), is at most ``requirements.max_frame_load``;
- ``min_stiffness``, ``min_frequency`` (only when the spec asks, or the figures
  ``task_min_stiffness`` / ``task_lowest_frequency`` are wanted): the least
  stiffness [N/m] and the lowest natural frequency [Hz] over the feasible poses
  of the task box (:mod:`cdpr_design.workspaces.stiffness`) are at least
  ``requirements.min_stiffness`` / ``requirements.min_frequency``;
- ``min_acceleration`` (only when the spec asks): the least acceleration radius
  [m/s^2] over the task box (:mod:`cdpr_design.workspaces.acceleration`; 0 when a
  task pose is not feasible) is at least ``requirements.min_acceleration``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Iterable

import numpy as np

from cdpr_design.design import sizing as sz
from cdpr_design.design.envelope import task_grid
from cdpr_design import workspaces as ws
from cdpr_design.model import spec
from cdpr_design.model.catalogue import Catalogue
from cdpr_design.model.design import Design

CHECKS = ("task_box", "min_margin", "min_fraction", "motors")
#: Checks whose columns a row has only when the spec asks for them (or their figures are wanted):
#: (check, requirement, figure of the task box, summary key of the task sweep).
STIFFNESS_CHECKS = (("min_stiffness", "min_stiffness", "task_min_stiffness", "min_stiffness"),
                    ("min_frequency", "min_frequency", "task_lowest_frequency", "lowest_frequency"))
#: The task box's stiffness figures (:data:`STIFFNESS_CHECKS`).
STIFFNESS_FIGURES = frozenset(f for _, _, f, _ in STIFFNESS_CHECKS)

#: Figures of the static workspace sweep (the whole workspace grid).
WORKSPACE_FIGURES = frozenset({"kind", "poses", "feasible", "fraction", "measure", "min_margin", "max_margin",
                               "max_tension"})
#: Figures of the workspace's boundary and of the frame loads (a sweep planned with ``solid``):
#: the area or volume inside the boundary, its perimeter or surface, the largest force on the frame.
SOLID_FIGURES = frozenset({"boundary_measure", "boundary_surface", "max_frame_load"})
#: Figures of the motor sizing (also ``peak_tension_<cable>`` and ``motor_<cable>``).
SIZING_FIGURES = frozenset({"sizing_poses", "peak_tension", "peak_cable_speed", "peak_motor_torque",
                            "rms_motor_torque", "peak_motor_speed", "motor", "torque_margin", "speed_margin",
                            "implied_tension_max", "tension_max", "drum_radius", "gear_ratio", "safety_factor",
                            "duty_cycle"})


@dataclass
class Evaluation:
    """Everything :func:`evaluate_full` computed (the row plus the results behind it)."""

    row: dict
    workspace: ws.WorkspaceResult | None  # None: not asked for (``figures``)
    task: ws.WorkspaceResult | None
    sizing: sz.SizingResult | None  # None: not asked for (``figures``)

    @property
    def passed(self) -> bool:
        return bool(self.row["checks_passed"])


def _f(x):
    """A plain float, or None for None / NaN / inf."""
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def _task_kind(design: Design) -> str:
    return "wrench-feasible" if design.workspace.external_wrench is not None else "static"


def stiffness_asked(design: Design, figures: Iterable[str] | None = None) -> bool:
    """Whether the task box's stiffness is asked for: ``requirements.min_stiffness`` or
    ``min_frequency``, or one of :data:`STIFFNESS_FIGURES` among ``figures``."""
    req = design.requirements
    return (req.min_stiffness is not None or req.min_frequency is not None
            or bool(set(figures or ()) & STIFFNESS_FIGURES))


def task_sweep(design: Design, step: float | None = None, progress=None, engine: str = "auto",
               stiffness: bool = False, accelerations: bool = False):
    """Sweep the task box: (result, least margin over every task pose); ``stiffness`` adds the
    least stiffness and the lowest natural frequency over its feasible poses to the result's summary,
    ``accelerations`` the least and greatest acceleration radius (asked for by
    ``requirements.min_acceleration``: a refusal names it).

    The least margin counts infeasible poses (negative margins) and is -inf
    when a task pose has no margin (a rank-deficient structure matrix, or a
    hanging effector rejected for its tilt or tensions: NaN).
    """
    g = task_grid(design, step)
    if g is None:
        return None, None
    least = [math.inf]

    def on_chunk(c):
        mg = c.margin
        if np.isnan(mg).any():
            least[0] = -math.inf
        elif mg.size:
            least[0] = min(least[0], float(mg.min()))

    analysis = ws.Analysis(kind=_task_kind(design), engine=engine, stiffness=stiffness, accelerations=accelerations,
                           accelerations_by="requirements.min_acceleration")
    res = ws.run(design, analysis, grid=g, on_chunk=on_chunk, progress=progress, keep_maps=False, tilt=False)
    return res, least[0]


def motors_asked(design: Design, motor: str | None = None) -> bool:
    """Whether the ``motors`` check is asked for (a motor named, or max_speed / max_acceleration given)."""
    req = design.requirements
    return (any(c.winch.motor for c in design.cables) or motor is not None
            or req.max_speed is not None or req.max_acceleration is not None)


def parts_needed(design: Design, figures: Iterable[str] | None, motor: str | None = None) -> tuple[bool, bool]:
    """(workspace, sizing): whether ``figures`` or the spec's checks need the workspace sweep / the sizing.

    The task box is always swept (it is small).  The workspace is needed by its
    own figures (:data:`WORKSPACE_FIGURES`), by ``requirements.min_fraction``, and
    when the spec has no task box (the margin check then reads the workspace);
    the sizing by its figures (:data:`SIZING_FIGURES`, per-cable ones) and the
    ``motors`` check.  ``figures`` None: everything.
    """
    if figures is None:
        return True, True
    figures = set(figures)
    req = design.requirements
    workspace = (req.task_box is None or req.min_fraction is not None or req.max_frame_load is not None
                 or bool(figures & (WORKSPACE_FIGURES | SOLID_FIGURES)))
    sizing = motors_asked(design, motor) or any(
        f in SIZING_FIGURES or f.startswith(("peak_tension_", "motor_")) for f in figures)
    return workspace, sizing


def evaluate_full(design: Design, *, step: float | None = None, catalogue: Catalogue | None = None,
                  samples=None, safety_factor: float | None = None, motor: str | None = None,
                  workspace_result: ws.WorkspaceResult | None = None, keep_maps: bool = False,
                  progress: Callable[[int, int], None] | None = None, engine: str = "auto",
                  figures: Iterable[str] | None = None) -> Evaluation:
    """Workspace, task box, motor sizing and checks of one design.

    Parameters
    ----------
    design : Design
    step : float, optional
        Grid step [m] for the workspace and the task box.
    catalogue : Catalogue, optional
        Default: the shipped catalogue (``cdpr_design/data/motors.yaml``).
    samples : trajectory samples, optional
        Duty cycle for the RMS torque (:func:`cdpr_design.motion.trajectory.sample`).
    safety_factor, motor : see :func:`cdpr_design.design.sizing.size_motors`.
    workspace_result : WorkspaceResult, optional
        A static sweep already made (``report`` writes the workspace files first).
    engine : {'auto', 'numba', 'numpy'}
        Engine of the grid sweeps (:func:`cdpr_design.workspaces.run`).
    figures : names of the figures wanted, optional
        Skip the workspace sweep or the sizing when neither these figures nor
        the spec's checks need it (:func:`parts_needed`); the skipped part's
        figures are then absent from the row (the others are the same
        numbers).  Default: everything.
    """
    if catalogue is None:
        catalogue = spec.load_catalogue()
    need_ws, need_sizing = parts_needed(design, figures, motor)
    wres = workspace_result
    if wres is None and need_ws:
        # the figures and checks use no hanging tilt of a held effector (report passes its own sweep)
        solid = (figures is None or bool(set(figures) & SOLID_FIGURES)
                 or design.requirements.max_frame_load is not None)
        wres = ws.run(design, ws.Analysis(engine=engine), step=step, keep_maps=keep_maps, progress=progress,
                      tilt=False, solid=solid)
    stiffness = stiffness_asked(design, figures) and task_grid(design, step) is not None
    accelerations = design.requirements.min_acceleration is not None and task_grid(design, step) is not None
    task, task_least = task_sweep(design, step, engine=engine, stiffness=stiffness, accelerations=accelerations)
    sizing = None
    if need_sizing:
        from cdpr_design.statics.robot import Analysis, resolve

        sz.check_options(design, catalogue, safety_factor, motor)  # the options first, then the robot
        sizing = sz.size_motors(resolve(design, Analysis(command="size-motors")), catalogue, step=step,
                                samples=samples, safety_factor=safety_factor, motor=motor, engine=engine)
    row = _workspace_figures(design, wres, task, task_least)
    if sizing is not None:
        row.update(_sizing_figures(sizing))
    row.update(_checks(design, wres, task, task_least, sizing, motor, stiffness, accelerations))
    # per-cable figures last (their number depends on the design)
    for a in sizing.axes if sizing is not None else ():
        row[f"peak_tension_{a.cable}"] = _f(a.peak_tension)
        row[f"motor_{a.cable}"] = a.motor
    return Evaluation(row, wres, task, sizing)


def _workspace_figures(design: Design, wres: ws.WorkspaceResult | None, task: ws.WorkspaceResult | None,
                       task_least: float | None) -> dict:
    """The workspace's (unless ``wres`` is None) and the task box's figures (margins [N], tensions [N],
    fractions)."""
    row: dict = {"name": design.name, "motion": design.motion.name, "cables": design.m}
    if wres is not None:
        row.update({
            "kind": wres.kind, "poses": int(wres.poses), "feasible": int(wres.feasible),
            "fraction": float(wres.fraction), "measure": float(wres.measure),
            "min_margin": _f(wres.min_margin), "max_margin": _f(wres.max_margin),
            "max_tension": _f(np.nanmax(wres.max_tension)) if np.isfinite(wres.max_tension).any() else None,
        })
        if wres.boundary is not None:
            s = wres.summary()
            row.update(boundary_measure=_f(s["boundary_measure"]), boundary_surface=_f(s["boundary_surface"]),
                       max_frame_load=_f(s["frame_loads"]["max_force"]))
    if task is not None:
        row.update(task_poses=int(task.poses), task_feasible=int(task.feasible),
                   task_fraction=float(task.fraction), task_min_margin=_f(task_least)
                   if task_least != -math.inf else None)
    else:
        row.update(task_poses=None, task_feasible=None, task_fraction=None, task_min_margin=None)
    return row


def _sizing_figures(sizing: sz.SizingResult) -> dict:
    """The worst axis's sizing figures: peaks over the cables, least margins, the motors chosen."""
    axes = sizing.axes
    motors = sorted({a.motor for a in axes})
    return dict(
        sizing_poses=sizing.envelope.poses,
        peak_tension=_f(max(a.peak_tension for a in axes)),
        peak_cable_speed=_f(max(a.peak_cable_speed for a in axes)),
        peak_motor_torque=_f(max(a.peak_motor_torque for a in axes)),
        rms_motor_torque=_f(max(a.rms_motor_torque for a in axes)),
        peak_motor_speed=_f(max(a.peak_motor_speed for a in axes)),
        motor=";".join(motors) if all(motors) else "",
        torque_margin=_f(min(a.torque_margin for a in axes)),
        speed_margin=_f(min(a.speed_margin for a in axes)),
        implied_tension_max=_f(min(a.implied_tension_max for a in axes)),
        tension_max=_f(min(a.tension_max for a in axes)),
        drum_radius=";".join(sorted({f"{a.drum_radius:g}" for a in axes})),
        gear_ratio=";".join(sorted({f"{a.gear_ratio:g}" for a in axes})),
        safety_factor=sizing.safety_factor, duty_cycle=sizing.cycle,
    )


def _checks(design: Design, wres: ws.WorkspaceResult | None, task: ws.WorkspaceResult | None,
            task_least: float | None, sizing: sz.SizingResult | None, motor: str | None,
            stiffness: bool = False, accelerations: bool = False) -> dict:
    """The requirement figures and limits, ``check_<name>`` (True, False, None) and ``checks_passed``.

    ``wres`` and ``sizing`` may be None only where :func:`parts_needed` says the checks do not need them."""
    req = design.requirements
    row: dict = {}
    checks: dict = {}
    checks["task_box"] = (task.feasible == task.poses) if task is not None else None
    if req.min_margin is not None:
        figure = task_least if task is not None else wres.min_margin
        checks["min_margin"] = figure is not None and figure >= req.min_margin
        row["min_margin_figure"] = _f(figure) if figure is not None else None
    else:
        checks["min_margin"] = None
        row["min_margin_figure"] = _f(task_least) if task is not None else _f(wres.min_margin)
    row["req_min_margin"] = req.min_margin
    checks["min_fraction"] = (wres.fraction >= req.min_fraction) if req.min_fraction is not None else None
    row["req_min_fraction"] = req.min_fraction
    checks["motors"] = sizing.ok if motors_asked(design, motor) else None
    if req.max_frame_load is not None:  # the workspace's loads on the frame (a solid sweep)
        load = row.get("max_frame_load") if "max_frame_load" in row else _max_frame_load(wres)
        row["max_frame_load"], row["req_max_frame_load"] = load, req.max_frame_load
        checks["max_frame_load"] = load is not None and load <= req.max_frame_load
    if stiffness:  # the task box's least stiffness and lowest frequency (STIFFNESS_CHECKS)
        s = task.summary()
        for name, req_name, figure, key in STIFFNESS_CHECKS:
            value, limit = _f(s.get(key)), getattr(req, req_name)
            row[figure], row[f"req_{req_name}"] = value, limit
            checks[name] = None if limit is None else (value is not None and value >= limit)
    if accelerations:  # the least acceleration radius over the task box: 0 where a task pose is not held
        least = task.summary().get("min_acceleration_radius") if task.feasible == task.poses else 0.0
        row["task_min_acceleration"], row["req_min_acceleration"] = _f(least), req.min_acceleration
        checks["min_acceleration"] = least is not None and least >= req.min_acceleration
    for name in checks:
        row[f"check_{name}"] = None if checks[name] is None else bool(checks[name])
    row["checks_passed"] = all(v is not False for v in checks.values())
    return row


def _max_frame_load(wres: ws.WorkspaceResult | None) -> float | None:
    """The largest force [N] on the frame at an outlet over the feasible grid poses (None: none feasible)."""
    if wres is None or wres.frame_loads is None:
        return None
    return _f(wres.summary()["frame_loads"]["max_force"])


def evaluate(design: Design, *, step: float | None = None, catalogue: Catalogue | None = None,
             samples=None, safety_factor: float | None = None, motor: str | None = None,
             engine: str = "auto", figures: Iterable[str] | None = None) -> dict:
    """The headline figures of one design: one ``design_report.csv`` row (plain, picklable values).

    See :func:`evaluate_full` for the parameters and the module docstring for
    the checks.
    """
    return evaluate_full(design, step=step, catalogue=catalogue, samples=samples,
                         safety_factor=safety_factor, motor=motor, engine=engine, figures=figures).row


def check_table(row: dict) -> list[dict]:
    """The requirement table of ``check``: one dict per requirement asked for.

    Keys: ``requirement``, ``figure`` (text), ``limit`` (text), ``passed`` (bool).
    """
    out = []

    def num(v, unit=""):
        return "—" if v is None else f"{v:.4g}{unit}"

    if row["check_task_box"] is not None:
        out.append({"requirement": "task_box", "figure": f"{row['task_feasible']} of {row['task_poses']} poses feasible",
                    "limit": "all", "passed": row["check_task_box"]})
    if row["check_min_margin"] is not None:
        out.append({"requirement": "min_margin", "figure": num(row["min_margin_figure"], " N"),
                    "limit": f">= {row['req_min_margin']:g} N", "passed": row["check_min_margin"]})
    if row["check_min_fraction"] is not None:
        out.append({"requirement": "min_fraction", "figure": num(row["fraction"]),
                    "limit": f">= {row['req_min_fraction']:g}", "passed": row["check_min_fraction"]})
    for name, req_name, figure, _ in STIFFNESS_CHECKS:
        if row.get(f"check_{name}") is not None:
            unit = " N/m" if name == "min_stiffness" else " Hz"
            out.append({"requirement": name, "figure": num(row[figure], unit),
                        "limit": f">= {row[f'req_{req_name}']:g}{unit}", "passed": row[f"check_{name}"]})
    if row.get("check_max_frame_load") is not None:
        out.append({"requirement": "max_frame_load", "figure": num(row["max_frame_load"], " N"),
                    "limit": f"<= {row['req_max_frame_load']:g} N", "passed": row["check_max_frame_load"]})
    if row.get("check_min_acceleration") is not None:
        out.append({"requirement": "min_acceleration", "figure": num(row["task_min_acceleration"], " m/s²"),
                    "limit": f">= {row['req_min_acceleration']:g} m/s²", "passed": row["check_min_acceleration"]})
    if row["check_motors"] is not None:
        out.append({"requirement": "motors", "figure": f"{row['motor'] or 'none fits'}: torque margin "
                    f"{num(row['torque_margin'])}, speed margin {num(row['speed_margin'])}",
                    "limit": ">= 1", "passed": row["check_motors"]})
    return out
