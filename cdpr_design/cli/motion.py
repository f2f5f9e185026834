"""``trajectory``, ``simulate`` and ``compare`` (the paper's Tables 1 and 2)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Optional

import typer

from cdpr_design.cli.common import (CableModelOpt, Format, FormatOpt, JsonOpt, OutOpt, OverwriteOpt, QuietOpt,
                                    SpecArg, bars, command, emit_json, fmt, info, load_design, out_console,
                                    summary_table, table)
from cdpr_design.errors import CheckFailed

if TYPE_CHECKING:
    from rich.table import Table

CycleOpt = Annotated[Optional[float], typer.Option(
    "--cycle-time", help="Sample period [s] (default: the trajectory's cycle_time, else 0.001).", min=1e-5, max=1.0)]
NameArg = Annotated[str, typer.Argument(help="Name of a path in the spec's trajectories: section.")]


TimeOptimalOpt = Annotated[bool, typer.Option(
    "--time-optimal", help="Time the path as fast as the robot allows (tensions, winch motor speed and peak "
                           "torque, the path's own speed and acceleration as upper limits), rest at every corner.")]


def tension_ranges(summary: dict, cables) -> str:
    """``c1: 5–20, c2: ...``: each cable's tension range [N]."""
    return ", ".join(f"{c}: {fmt(summary['min_tension'][c])}–{fmt(summary['max_tension'][c])}" for c in cables)


def segments_table(title: str, segments: list[dict]) -> Table:
    """The paper's Table 2 layout: mean target and mean actual position per straight segment."""
    t = table(title)
    for head in ("segment", "axis", "mean target [mm]", "mean actual [mm]", "error [mm]", "error [%]"):
        t.add_column(head, justify="right")
    for r in segments:
        t.add_row(str(r["segment"]), r["axis"], f"{1e3 * r['mean_target']:.3f}", f"{1e3 * r['mean_actual']:.3f}",
                  f"{1e3 * r['error']:+.3f}", f"{r['error_pct']:.3f}")
    return t


def setpoint_rows(summary: dict) -> list:
    """Summary rows of a real cable model: the largest error of ideal set-points, unsolved samples."""
    if "cable_model" not in summary:
        return []
    err = ", ".join(f"{c}: {fmt(None if v is None else 1e3 * v)}" for c, v in summary["max_setpoint_error"].items())
    return [("cable model", summary["cable_model"]), ("ideal set-point error [mm]", err),
            ("samples without set-points", f"{summary['unsolved_samples']:,}")]


def time_optimal_rows(summary: dict) -> list:
    """Summary rows of a time-optimal timing: the profile's duration it replaces, the constraints active."""
    t = summary.get("time_optimal")
    if t is None:
        return []
    shares = ", ".join(f"{k} {100 * v:.0f} %" for k, v in t["active"].items() if v > 0)
    return [("profiled duration [s]", t["profiled_duration"]), ("active constraints", shares)]


def delay_text(delay: dict) -> str:
    """``x: 0.12, y: ...``: delays in [ms] (given in [s])."""
    return ", ".join(f"{k}: {fmt(None if v is None else 1e3 * v)}" for k, v in delay.items())


@command
def trajectory_cmd(
    spec: SpecArg,
    name: NameArg,
    cycle_time: CycleOpt = None,
    check: Annotated[bool, typer.Option(
        "--check", help="Exit 1 when a sample's tensions leave the cable bounds.")] = False,
    time_optimal: TimeOptimalOpt = False,
    collisions: Annotated[bool, typer.Option(
        "--collisions", help="Also check every sample for cable-cable, cable-effector and effector-frame "
                             "interference; feasible = tensions within the bounds and collision free "
                             "(column collision_free).")] = False,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
    cable_model: CableModelOpt = None,
    format: FormatOpt = Format.csv,
):
    """Sample a spec path at a fixed cycle: trajectory.csv, trajectory.png, trajectory_axes.png, trajectory.json."""
    from cdpr_design.cli import env
    from cdpr_design.jobs import motion as job

    design = load_design(spec, cable_model)
    samples, s, out_dir = job.trajectory(design, name, cycle_time, out, overwrite, engine=env.engine(),
                                         format=format.value, time_optimal=time_optimal, collisions=collisions)
    if json_:
        emit_json(s)
    else:
        out_console.print(summary_table(
            f"{design.name} — trajectory {name}",
            [("samples", f"{s['samples']:,}"), ("cycle time [ms]", 1e3 * s["cycle_time"]),
             ("duration [s]", s["duration"]), ("peak speed [m/s]", s["max_speed"]),
             ("peak acceleration [m/s²]", s["max_acceleration"]),
             ("tension range [N]", tension_ranges(s, samples.cable_names)),
             ("feasible", "yes" if s["feasible"] else f"no ({s['infeasible_samples']} samples)"),
             *([("colliding samples", f"{s['collision_samples']:,}")] if "collision_samples" in s else []),
             *setpoint_rows(s), *time_optimal_rows(s),
             ("files", str(out_dir.path))]))
        if s.get("time_optimal", {}).get("limits_note"):
            info(quiet, f"note: {s['time_optimal']['limits_note']}")
    if check and not s["feasible"]:
        raise CheckFailed(f"trajectory {name}: {s['infeasible_samples']} samples with tensions outside the bounds"
                          + (f" or colliding ({s['collision_samples']})" if "collision_samples" in s else ""))


@command
def simulate(
    spec: SpecArg,
    name: NameArg,
    delay: Annotated[float, typer.Option(
        "--delay", help="Transport delay of the set-points [s] (the paper's ADS path: 0.11-0.15).",
        min=0.0, max=10.0)] = 0.0,
    servo_bandwidth: Annotated[float, typer.Option(
        "--servo-bandwidth", help="Position-loop bandwidth of each winch axis [rad/s].", min=1e-3, max=1e6)] = 300.0,
    feedforward: Annotated[bool, typer.Option(
        "--feedforward/--no-feedforward", help="Velocity feed-forward in the axis position loop.")] = True,
    compensate_stretch: Annotated[bool, typer.Option(
        "--stretch-compensation/--no-stretch-compensation",
        help="Take up each cable's expected elastic stretch T/k in the command.")] = True,
    cable_damping: Annotated[float, typer.Option(
        "--cable-damping", help="Damping ratio of the axial cable mode.", min=0.0, max=100.0)] = 0.7,
    timestep: Annotated[float, typer.Option("--timestep", help="Physics step [s].", min=1e-6, max=0.01)] = 5e-4,
    hold: Annotated[Optional[float], typer.Option(
        "--hold", help="Time [s] to keep the last set-point at the end (default 0.5 s + the delay).",
        min=0.0, max=60.0)] = None,
    cycle_time: CycleOpt = None,
    cable_segments: Annotated[Optional[int], typer.Option(
        "--cable-segments", help="Segments of each sagging cable in the MuJoCo model, 2-200 (default 16).")] = None,
    time_optimal: TimeOptimalOpt = False,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
    cable_model: CableModelOpt = None,
    format: FormatOpt = Format.csv,
):
    """Run a spec path on the MuJoCo model of the robot: simulation.csv, simulation.json, simulation.png."""
    from cdpr_design.jobs import motion as job

    design = load_design(spec, cable_model)
    settings = job.SimulateSettings(
        delay=delay, servo_bandwidth=servo_bandwidth, feedforward=feedforward, compensate_stretch=compensate_stretch,
        cable_damping=cable_damping, timestep=timestep, hold=hold, cycle_time=cycle_time,
        cable_segments=cable_segments, format=format.value, time_optimal=time_optimal)
    result, s, samples, out_dir = job.simulate(design, name, settings, out, overwrite,
                                               progress=bars(quiet or json_, min_total=2000))
    if json_:
        emit_json(s)
        return
    out_console.print(summary_table(
        f"{design.name} — simulation of {name} (delay {1e3 * delay:g} ms)",
        [("samples", f"{s['samples']:,}"), ("RMS position error [mm]", 1e3 * s["rms_error"]),
         ("max position error [mm]", 1e3 * s["max_error"]), ("delay [ms]", delay_text(s["delay"])),
         ("tension range [N]", tension_ranges(s, result.cable_names)),
         ("files", str(out_dir.path))]))
    if s["segments"]:
        out_console.print(segments_table("straight segments (the paper's Table 2)", s["segments"]))
    if not samples.all_feasible:
        info(quiet, "note: the trajectory's tensions leave the cable bounds somewhere (see trajectory --check)")


@command
def compare(
    target: Annotated[Path, typer.Argument(help="CSV log of the target run (set-points or a reference).")],
    actual: Annotated[Path, typer.Argument(help="CSV log of the actual run (simulation, prototype scope export).")],
    columns: Annotated[Optional[str], typer.Option(
        "--columns", help="Comma-separated columns to compare (default: every column in both).")] = None,
    rename: Annotated[Optional[list[str]], typer.Option(
        "--map", help="TARGET_COL=ACTUAL_COL: compare differently named columns (repeatable).")] = None,
    max_delay: Annotated[Optional[float], typer.Option(
        "--max-delay", help="Largest delay searched [s] (default: half the record).", min=1e-6, max=1e6)] = None,
    out: Annotated[Optional[Path], typer.Option(
        "--out", help="Folder for comparison.json (default: nothing written).")] = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
):
    """Compare two logs of the same motion: delay per column, position errors, per-segment table."""
    from cdpr_design.jobs import motion as job

    res, s, cols = job.compare(target, actual, columns, rename, max_delay, out, overwrite)
    if json_:
        emit_json(s)
        return
    t = table(f"compare {target.name} → {actual.name}")
    for head in ("column", "delay [ms]", "mean error", "RMS error", "max error"):
        t.add_column(head, justify="right")
    for c in cols:
        st = s["columns"][c]
        t.add_row(c, fmt(None if s["delay"][c] is None else 1e3 * s["delay"][c]), fmt(st["mean"]),
                  fmt(st["rms"]), fmt(st["max"]))
    out_console.print(t)
    if res.beyond:
        info(quiet, f"{', '.join(res.beyond)}: the delay lies beyond the window searched (--max-delay, default "
                    "half the record): no delay is given; search a wider window")
    pos = res.position_columns
    if pos:
        out_console.print(summary_table("position error (" + ",".join(pos) + ")",
                                        [("RMS [mm]", 1e3 * res.rms_error), ("max [mm]", 1e3 * res.max_error)]))
    if s["segments"]:
        out_console.print(segments_table("straight segments (the paper's Table 2)", s["segments"]))


def register(app: typer.Typer) -> None:
    app.command("trajectory")(trajectory_cmd)
    app.command()(simulate)
    app.command()(compare)
