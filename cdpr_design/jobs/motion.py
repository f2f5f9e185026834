"""The ``trajectory``, ``simulate`` and ``compare`` jobs, and sampling a spec trajectory by name."""

from __future__ import annotations

import io
import math
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from cdpr_design.errors import InputError, quote
from cdpr_design.io.files import OutputDir
from cdpr_design.io.inputs import MAX_LOG_BYTES, read_text
from cdpr_design.io.tables import read_csv_columns, read_log
from cdpr_design.io.columns import file_name
from cdpr_design.jobs.common import Progress, output_dir, stage, submit_pictures
from cdpr_design.jobs.tables import Timings, write_table
from cdpr_design.plots import motion as motion_plots


def require_trajectory(design, name: str, option: str):
    """The spec trajectory ``name``; an unknown name is an :class:`InputError` naming ``option``."""
    traj = design.trajectories.get(name)
    if traj is None:
        known = ", ".join(design.trajectories) or "none"
        raise InputError(f"{option}: no trajectory named {quote(name)} in the spec (known: {known})")
    return traj


def read_poses(path: str | Path, design, what: str) -> np.ndarray:
    """Poses of a ``csv`` trajectory: columns named after the motion's coordinates
    (``x,y[,z][,phi|rx,ry,rz]``; orientation optional), or a header-less table
    in that order.  Positions [m], angles [rad]."""
    p = Path(path)
    coords = list(design.motion.coords)
    pos = coords[: design.motion.dim]
    try:
        text = read_text(p, MAX_LOG_BYTES, encoding="utf-8-sig")  # a regular file of bounded size
    except InputError as exc:
        raise InputError(f"{what}: {exc}") from None
    first = next((line for line in text.splitlines() if line.strip()), None)
    if first is None:
        raise InputError(f"{what}: {p} is empty")
    try:
        [float(c) for c in first.split(",") if c.strip()]
        has_header = False
    except ValueError:
        has_header = True
    arr = _named_poses(p, coords, pos, what) if has_header else _bare_poses(p, text, coords, pos, what)
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{what}: {p} has empty or non-numeric cells")
    if arr.shape[0] < 2:
        raise InputError(f"{what}: {p} needs at least 2 poses, got {arr.shape[0]}")
    return arr


def _named_poses(p: Path, coords, pos, what: str) -> np.ndarray:
    cols = read_csv_columns(p, what)
    missing = [c for c in pos if c not in cols]
    if missing:
        raise InputError(f"{what}: {p} lacks column(s) {', '.join(missing)} (expected {','.join(coords)})")
    use = coords if all(c in cols for c in coords) else pos
    return np.stack([cols[c] for c in use], axis=1)


def _bare_poses(p: Path, text: str, coords, pos, what: str) -> np.ndarray:
    try:
        arr = np.loadtxt(io.StringIO(text), delimiter=",", ndmin=2)
    except ValueError as exc:
        raise InputError(f"{what}: {p}: {exc}") from None
    if arr.shape[1] not in (len(pos), len(coords)):
        raise InputError(f"{what}: {p} has {arr.shape[1]} columns; expected {len(pos)} or {len(coords)} "
                         f"({','.join(coords)})")
    return arr


def sample_named(robot, name: str, cycle_time: float | None = None, hold_end: float = 0.0,
                 option: str = "NAME", time_optimal: bool = False):
    """Sample spec trajectory ``name`` of the :class:`~cdpr_design.statics.robot.Robot` the command
    resolved (reading a csv path's poses) every ``cycle_time`` [s], holding the last set-point
    ``hold_end`` [s]; bad names, cycles and files are :class:`InputError`.  ``time_optimal``: timed
    as fast as the robot allows (:func:`timed_named`)."""
    return timed_named(robot, name, cycle_time, hold_end, option, time_optimal)[0]


def timed_named(robot, name: str, cycle_time: float | None = None, hold_end: float = 0.0,
                option: str = "NAME", time_optimal: bool = False):
    """:func:`sample_named`'s samples and, with ``time_optimal``, the
    :class:`~cdpr_design.motion.time_optimal.Timing` of the fastest profile the robot allows
    (:mod:`cdpr_design.motion.time_optimal`; else None)."""
    from cdpr_design.motion import time_optimal as to
    from cdpr_design.motion import trajectory as tr

    design = robot.design
    traj = require_trajectory(design, name, option)
    if cycle_time is not None and not (math.isfinite(cycle_time) and 1e-5 <= cycle_time <= 1.0):
        raise InputError(f"--cycle-time: expected 1e-5 to 1 s, got {cycle_time}")
    poses = None
    if traj.type == "csv":
        p = Path(traj.file)
        if not p.is_absolute() and design.source:
            p = Path(design.source).resolve().parent / p
        poses = read_poses(p, design, f"trajectories.{name}.file")
    try:
        if time_optimal:
            return to.sample(robot, name, cycle_time, csv_poses=poses, hold_end=hold_end)
        return tr.sample(robot, name, cycle_time, csv_poses=poses, hold_end=hold_end), None
    except (KeyError, ValueError) as exc:
        msg = str(exc)
        raise InputError(msg if msg.startswith(("trajectories.", "--")) else f"trajectories.{name}: {msg}") from None


def motion_robot(design, time_optimal: bool = False, collisions: bool = False):
    """The design resolved once for a motion command (``trajectory``, ``simulate``; ``time_optimal``:
    the path timed as fast as the robot allows; ``collisions``: every sample checked for
    interference): a refused combination is an :class:`InputError` with the reason
    (:data:`cdpr_design.statics.robot.REFUSALS`)."""
    from cdpr_design.statics.robot import Analysis, resolve

    return resolve(design, Analysis(command="motion", time_optimal=time_optimal, collisions=collisions))


def trajectory_samples(robot, name: str | None, time_optimal: bool = False):
    """The spec trajectory ``name`` of the command's resolved robot sampled at its own cycle (None:
    no trajectory), for ``--trajectory`` (``time_optimal``: timed as fast as the robot allows)."""
    if name is None:
        if time_optimal:
            raise InputError("--time-optimal: times a trajectory; give --trajectory NAME")
        return None
    return sample_named(robot, name, option="--trajectory", time_optimal=time_optimal)


def design_samples(design, name: str | None):
    """:func:`trajectory_samples` of ``design`` resolved for ``motion`` (:func:`motion_robot`) when
    a trajectory is named: the name is checked first (``--trajectory``), then the design's refusals."""
    if name is None:
        return None
    require_trajectory(design, name, "--trajectory")
    return trajectory_samples(motion_robot(design), name)


def path_map(design, engine: str = "auto"):
    """A static workspace map for the path picture (planar designs; coarse enough to be quick)."""
    if not design.motion.planar:
        return None
    from cdpr_design import workspaces as ws

    g = design.workspace.grid
    ext = max(h - l for l, h in zip(g.lower, g.upper))
    step = max(max(g.step), ext / 200.0)
    try:
        return ws.run(design, ws.Analysis(engine=engine), step=step)
    except Exception:  # noqa: BLE001 - the picture is drawn without the map
        return None


class TrajectoryRun(NamedTuple):
    samples: object  # motion.trajectory.Samples
    summary: dict
    out: OutputDir


def trajectory(design, name: str, cycle_time: float | None = None, out: str | Path | None = None,
               overwrite: bool = False, engine: str = "auto", format: str = "csv",
               time_optimal: bool = False, collisions: bool = False) -> TrajectoryRun:
    """The ``trajectory`` command: sample ``name`` every ``cycle_time`` [s]; write trajectory.csv
    (``format='parquet'``: ``.parquet``), trajectory.json, trajectory.png and trajectory_axes.png
    into ``out`` (the pictures are drawn while the table is written).  ``time_optimal``: timed as
    fast as the robot allows (:mod:`cdpr_design.motion.time_optimal`), the JSON's ``time_optimal``
    object and ``time_optimal.png`` added.  ``collisions``: every sample checked for interference
    (column ``collision_free``, ``feasible`` collision free too, JSON ``collision_samples`` and
    ``collisions_by_kind``; sagging cables along their catenaries)."""
    timings = Timings()
    robot = motion_robot(design, time_optimal, collisions)
    with timings.phase("sweep_s"):
        samples, timing = timed_named(robot, name, cycle_time, time_optimal=time_optimal)
    out_dir = output_dir(design, out, overwrite)
    files = [file_name("trajectory", format), "trajectory.json", "trajectory.png", "trajectory_axes.png"]
    for f in files + (["time_optimal.png"] if time_optimal else []):
        out_dir.target(f)  # a foreign file (or a folder) of that name: refused before any work
    with timings.phase("pictures_s"):
        pmap = path_map(design, engine)
    with out_dir:  # every file put in place together at the end
        pending = submit_pictures(out_dir, [
            ("trajectory.png", motion_plots.trajectory_path_figure, (design, samples, pmap)),
            ("trajectory_axes.png", motion_plots.trajectory_axes_figure, (samples,)),
        ] + ([("time_optimal.png", motion_plots.time_optimal_figure, (design, name, timing))] if time_optimal
             else []), timings=timings)
        with timings.phase("write_s"):
            write_table(out_dir, "trajectory", samples.columns(), format, design, trajectory=name,
                        cycle_time=samples.cycle_time)
        pending.wait()
        s = samples.summary()
        if timing is not None:
            s["time_optimal"] = timing.summary()
        s["timings"] = timings.as_dict()
        out_dir.write_json("trajectory.json", s)
    return TrajectoryRun(samples, s, out_dir)


#: Ranges of the ``simulate`` settings: (option, low, high).
_SIM_RANGES = {"delay": ("--delay", 0.0, 10.0), "servo_bandwidth": ("--servo-bandwidth", 1e-3, 1e6),
               "cable_damping": ("--cable-damping", 0.0, 100.0), "timestep": ("--timestep", 1e-6, 0.01)}


def _check_simulation(settings: dict, hold: float | None) -> None:
    for key, (opt, lo, hi) in _SIM_RANGES.items():
        v = settings[key]
        if not (math.isfinite(v) and lo <= v <= hi) or (opt in ("--servo-bandwidth", "--timestep") and v <= 0):
            raise InputError(f"{opt}: expected a number in [{lo:g}, {hi:g}], got {v}")
    if hold is not None and not (math.isfinite(hold) and 0 <= hold <= 60):
        raise InputError(f"--hold: expected 0 to 60 s, got {hold}")


class SimulationRun(NamedTuple):
    result: object  # motion.run.SimulationResult
    summary: dict
    samples: object
    out: OutputDir


@dataclass(frozen=True)
class SimulateSettings:
    """The options of a ``simulate`` run (docs/cli.md): the set-points' transport ``delay`` [s],
    each axis' position-loop ``servo_bandwidth`` [rad/s], the velocity ``feedforward``,
    ``compensate_stretch`` (each cable's expected stretch taken up in the command), the axial
    cable mode's ``cable_damping`` ratio, the physics ``timestep`` [s], ``hold`` [s] the last
    set-point kept at the end (default 0.5 s + the delay), the samples' ``cycle_time`` [s]
    (default the spec's), ``cable_segments`` of each sagging cable (2 to 200), the table
    ``format`` (``csv`` or ``parquet``) and ``time_optimal`` (the path timed as fast as the robot
    allows, :mod:`cdpr_design.motion.time_optimal`)."""

    delay: float = 0.0
    servo_bandwidth: float = 300.0
    feedforward: bool = True
    compensate_stretch: bool = True
    cable_damping: float = 0.7
    timestep: float = 5e-4
    hold: float | None = None
    cycle_time: float | None = None
    cable_segments: int | None = None
    format: str = "csv"
    time_optimal: bool = False


def simulate(design, name: str, settings: SimulateSettings = SimulateSettings(), out: str | Path | None = None,
             overwrite: bool = False, *, progress: Progress | None = None) -> SimulationRun:
    """The ``simulate`` command: run trajectory ``name`` on the MuJoCo model with ``settings``
    (:class:`SimulateSettings`); write simulation.csv (``format='parquet'``: ``.parquet``),
    simulation.json and simulation.png into ``out`` (``overwrite``: replace foreign files).
    With elastic or sagging cables a sample without set-points is an InputError."""
    from cdpr_design.motion import simulation as sim
    from cdpr_design.motion.run import simulate

    o = settings
    timings = Timings()
    physics = {"delay": o.delay, "servo_bandwidth": o.servo_bandwidth, "cable_damping": o.cable_damping,
                "timestep": o.timestep}
    _check_simulation(physics, o.hold)
    if o.cable_segments is not None and not 2 <= o.cable_segments <= 200:
        raise InputError(f"--cable-segments: expected 2 to 200, got {o.cable_segments}")
    robot = motion_robot(design, o.time_optimal)
    samples = sample_named(robot, name, o.cycle_time, hold_end=(0.5 + o.delay) if o.hold is None else o.hold,
                           time_optimal=o.time_optimal)
    if samples.cycle_time < o.timestep:
        raise InputError(f"--timestep: {o.timestep} s is longer than the cycle time {samples.cycle_time} s")
    out_dir = output_dir(design, out, overwrite)
    for f in (file_name("simulation", o.format), "simulation.json", "simulation.png"):
        out_dir.target(f)  # a foreign file (or a folder) of that name: refused before the simulation
    with stage(progress, f"simulate {name}") as cb, timings.phase("sweep_s"):
        try:
            result = simulate(robot, samples, feedforward=o.feedforward, compensate_stretch=o.compensate_stretch,
                              progress=cb, cable_segments=o.cable_segments, **physics)
        except sim.SimulationError as exc:
            raise InputError(f"--timestep / --servo-bandwidth / --cable-damping: {exc}") from None
        except ValueError as exc:  # samples without set-points (the cable model has no solution there)
            raise InputError(f"trajectories.{name}: {exc}") from None
    with out_dir:  # every file put in place together at the end
        pending = submit_pictures(out_dir, [("simulation.png", motion_plots.simulation_figure, (result,))],
                                  timings=timings)
        with timings.phase("write_s"):
            write_table(out_dir, "simulation", result.columns(), o.format, design, trajectory=name,
                        settings=physics)
        pending.wait()
        s = result.summary()
        s["trajectory_feasible"] = samples.all_feasible
        s["timings"] = timings.as_dict()
        out_dir.write_json("simulation.json", s)
    return SimulationRun(result, s, samples, out_dir)


def _compare_columns(tgt: dict, act: dict, columns: str | None, rename) -> list[str]:
    """Apply ``--map`` renames to the ACTUAL columns; the columns to compare."""
    for item in rename or []:
        if item.count("=") != 1 or not all(item.split("=")):
            raise InputError(f"--map: expected TARGET_COL=ACTUAL_COL, got {quote(item)}")
        a, b = item.split("=")
        if b not in act:
            raise InputError(f"--map: ACTUAL has no column {quote(b)}")
        act[a] = act.pop(b)
    if columns is not None:
        cols = [c.strip() for c in columns.split(",") if c.strip()]
        for c in cols:
            for what, d in (("TARGET", tgt), ("ACTUAL", act)):
                if c not in d:
                    raise InputError(f"--columns: {what} has no numeric column {quote(c)}")
        return cols
    cols = [c for c in tgt if c in act and c not in ("segment", "feasible")]
    if not cols:
        raise InputError(f"TARGET and ACTUAL have no value column in common "
                         f"(TARGET: {quote(', '.join(tgt))}; ACTUAL: {quote(', '.join(act))}); use --map")
    return cols


def _refuse_empty_columns(tgt: dict, act: dict, empty_t: list, empty_a: list) -> None:
    """A column with numbers in one log and none in the other (every cell empty or NaN) is not
    silently left out of the comparison: an :class:`InputError` names it."""
    for what, empty, other in (("ACTUAL", empty_a, tgt), ("TARGET", empty_t, act)):
        lost = [c for c in empty if c in other and c not in ("segment", "feasible")]
        if lost:
            raise InputError(f"{what} column(s) {', '.join(quote(c) for c in lost)} hold no number (every cell "
                             "empty or NaN), so they cannot be compared; choose the columns with --columns")


class ComparisonRun(NamedTuple):
    comparison: object  # motion.compare.Comparison
    summary: dict
    columns: list


def compare(target: Path, actual: Path, columns: str | None = None, rename=None, max_delay: float | None = None,
            out: str | Path | None = None, overwrite: bool = False) -> ComparisonRun:
    """The ``compare`` command: two CSV logs of one motion; ``columns`` comma-separated (default
    the common ones), ``rename`` TARGET_COL=ACTUAL_COL items, ``max_delay`` [s]; ``out``: write
    comparison.json there (default: nothing written)."""
    from cdpr_design.motion import compare as cmp

    empty_t, empty_a = [], []
    t_t, tgt = read_log(target, "TARGET", empty_t)
    t_a, act = read_log(actual, "ACTUAL", empty_a)
    cols = _compare_columns(tgt, act, columns, rename)
    if columns is None:
        _refuse_empty_columns(tgt, act, empty_t, empty_a)
    if max_delay is not None and not (math.isfinite(max_delay) and max_delay > 0):
        raise InputError(f"--max-delay: expected a positive number of seconds, got {max_delay}")
    try:
        res = cmp.compare(t_t, tgt, t_a, act, columns=cols, max_delay=max_delay)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    s = res.to_json()
    s["target"], s["actual"] = str(target), str(actual)
    if out is not None:
        OutputDir(out, overwrite=overwrite).write_json("comparison.json", s)
    return ComparisonRun(res, s, cols)
