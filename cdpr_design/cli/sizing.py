"""``size-motors``, ``report`` and ``check``: motor sizing, the design report, requirement checks."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer

from cdpr_design.cli.common import (CableModelOpt, CatalogueOpt, ForceOpt, Format, FormatOpt, JsonOpt,
                                    MotorOpt, OutOpt, OverwriteOpt, QuietOpt, SafetyOpt, SpecArg, StepOpt,
                                    TrajectoryOpt, bars, command, emit_json, fmt, info, load_design,
                                    out_console, table)
from cdpr_design.errors import CheckFailed

if TYPE_CHECKING:
    from rich.table import Table


def sizing_table(design, result) -> Table:
    """One row per cable: peak tension, motor torques and speed, the motor and its margins."""
    t = table(f"{design.name} — motor sizing ({result.envelope.poses:,} {result.envelope.source} poses, "
              f"safety factor {result.safety_factor:g})")
    cols = [("cable", "cable"), ("T [N]", "peak_tension"), ("τ pk", "peak_motor_torque"),
            ("τ rms", "rms_motor_torque"), ("rpm", "peak_motor_speed"),
            ("motor", "motor"), ("τ mrg", "torque_margin"), ("n mrg", "speed_margin"),
            ("T lim [N]", "implied_tension_max")]
    for head, key in cols:
        t.add_column(head, no_wrap=key in ("motor", "cable"))
    for row in result.rows():
        cells = []
        for _, key in cols:
            v = row[key]
            cells.append((v or "none fits") if key == "motor" else fmt(v, 3))
        t.add_row(*cells)
    r0 = result.axes[0] if result.axes else None
    if r0 is not None:
        t.caption = (f"drum radius {r0.drum_radius:g} m, gear ratio {r0.gear_ratio:g} (cable {r0.cable}); "
                     "T: peak tension; τ [N m] at the motor; margins ≥ 1 pass; T lim = τ_peak i η / r")
    return t


def frame_load_console_table(design, rows: list[dict], total: dict) -> Table:
    """One row per cable: ``frame_loads.csv``'s forces [N] on the frame at its outlet."""
    axes = "xy" if design.motion.planar else "xyz"
    t = table(f"{design.name} — loads on the frame ({total['poses']:,} feasible workspace poses)")
    cols = [("cable", "cable"), ("max |F| [N]", "max_force")]
    cols += [(f"f{a} [N]", f"f{a}") for a in axes] + [("limit |F| [N]", "limit_max_force")]
    for head, key in cols:
        t.add_column(head, no_wrap=True)
    for r in rows:
        cells = [r["cable"], fmt(r["max_force"], 4)]
        cells += [f"{fmt(r[f'min_f{a}'], 3)} .. {fmt(r[f'max_f{a}'], 3)}" for a in axes]
        t.add_row(*cells, fmt(r["limit_max_force"], 4))
    tf, tm = total["total_force"]["max_magnitude"], total["total_moment"]["max_magnitude"]
    t.caption = (f"with the sweep's tensions; limit: each cable at its upper bound along its directions; total force "
                 f"≤ {fmt(tf, 4)} N, moment about the origin ≤ {fmt(tm, 4)} N m")
    return t


def checks_table(design, rows: list[dict]) -> Table:
    """One row per requirement: its figure, its limit, pass or FAIL."""
    t = table(f"{design.name} — requirements")
    for col in ("requirement", "figure", "limit", "result"):
        t.add_column(col)
    for r in rows:
        t.add_row(r["requirement"], r["figure"], r["limit"], "pass" if r["passed"] else "FAIL")
    return t


@command
def size_motors(
    spec: SpecArg,
    catalogue: CatalogueOpt = None,
    trajectory: TrajectoryOpt = None,
    safety_factor: SafetyOpt = None,
    motor: MotorOpt = None,
    step: StepOpt = None,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
    cable_model: CableModelOpt = None,
    format: FormatOpt = Format.csv,
    time_optimal: Annotated[bool, typer.Option(
        "--time-optimal", help="Size on the --trajectory timed as fast as the design allows.")] = False,
):
    """Motor, gearbox and drum sizing over the task workspace: motor_sizing.csv."""
    from cdpr_design.cli import env
    from cdpr_design.jobs import sizing as job

    design = load_design(spec, cable_model)
    result, out_dir, summary = job.size_motors(design, catalogue, trajectory, safety_factor, motor, step, out,
                                               overwrite, engine=env.engine(), format=format.value,
                                               time_optimal=time_optimal)
    if json_:
        emit_json(summary)
        return
    out_console.print(sizing_table(design, result))
    out_console.print(frame_load_console_table(design, summary["frame_loads_per_cable"], summary["frame_loads"]))
    info(quiet, f"duty cycle: {result.cycle}")
    for note in result.notes:
        info(quiet, f"note: {note}")
    info(quiet, f"wrote {out_dir.path / ('motor_sizing.' + format.value)}")


@command
def report(
    spec: SpecArg,
    catalogue: CatalogueOpt = None,
    trajectory: TrajectoryOpt = None,
    safety_factor: SafetyOpt = None,
    motor: MotorOpt = None,
    step: StepOpt = None,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    force: ForceOpt = False,
    overwrite: OverwriteOpt = False,
    cable_model: CableModelOpt = None,
    format: FormatOpt = Format.csv,
):
    """Every artefact for one design (workspace, motor sizing) plus design_report.csv and report.html."""
    from cdpr_design.cli import env
    from cdpr_design.jobs import sizing as job
    from cdpr_design.plots import worker as _picture_worker

    with _picture_worker.take(enabled=env.picture_worker_enabled()) as pictures:  # matplotlib's import overlaps the spec and the sweep
        design = load_design(spec, cable_model)
        e, checks, out_dir, timings = job.report(design, catalogue, trajectory, safety_factor, motor, step, force,
                                                 out, overwrite, pictures=pictures, engine=env.engine(),
                                                 progress=bars(quiet or json_, min_total=500_000),
                                                 format=format.value)
    if json_:
        emit_json({**e.row, "checks": checks, "timings": timings})
        return
    out_console.print(sizing_table(design, e.sizing))
    if e.workspace is not None and e.workspace.frame_loads is not None:
        s = e.workspace.summary()["frame_loads"]
        cols = e.workspace.frame_loads.rows(design.cable_names)
        rows = [{k: v[i] for k, v in cols.items()} for i in range(design.m)]
        out_console.print(frame_load_console_table(design, rows, s))
    if checks:
        out_console.print(checks_table(design, checks))
    ext = format.value
    info(quiet, f"wrote workspace.{ext}, workspace.png, tension_map.png, summary.json, motor_sizing.{ext}, "
                f"design_report.{ext}, report.json, report.html to {out_dir.path}")


@command
def check(
    spec: SpecArg,
    catalogue: CatalogueOpt = None,
    trajectory: TrajectoryOpt = None,
    safety_factor: SafetyOpt = None,
    motor: MotorOpt = None,
    step: StepOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    cable_model: CableModelOpt = None,
    certify: Annotated[bool, typer.Option(
        "--certify", help="Also prove the whole task box feasible by interval analysis (as "
                          "requirements.certified: true).")] = False,
):
    """Test the spec's requirements: one line per requirement; exit 0 all pass, 1 otherwise."""
    from cdpr_design.cli import env
    from cdpr_design.jobs import sizing as job

    design = load_design(spec, cable_model)
    e, checks = job.check(design, catalogue, trajectory, safety_factor, motor, step,
                          progress=bars(quiet or json_, min_total=500_000), engine=env.engine())
    passed = e.passed
    if certify or design.requirements.certified:
        from cdpr_design.jobs.certify import certify_task

        row = certify_task(design)
        checks.append(row)
        passed = passed and row["passed"]
        if not row["passed"] and not json_:
            info(quiet, certify_failure(row))
    if json_:
        emit_json({"name": design.name, "passed": passed, "checks": checks, "figures": e.row})
    else:
        if checks:
            out_console.print(checks_table(design, checks))
        else:
            out_console.print(f"{design.name}: the spec's requirements section asks for nothing to check")
    if not passed:
        failed = [c["requirement"] for c in checks if not c["passed"]]
        raise CheckFailed("" if json_ else f"{design.name}: {', '.join(failed)}")


def certify_failure(row: dict) -> str:
    """The message of a failed ``certified`` check: the box not proven and the witness pose."""
    b = row["unproven_box"]
    msg = (f"certified: could not prove the box [{', '.join(f'{v:.6g}' for v in b['lower'])}] .. "
           f"[{', '.join(f'{v:.6g}' for v in b['upper'])}] ({b['status']})")
    w = row.get("witness")
    if w:
        reason = "infeasible" if not w["feasible"] else f"margin {w['margin']:.4g} N"
        msg += f"; at the pose ({', '.join(f'{v:.6g}' for v in w['pose'])}): {reason}"
        if w["feasible"]:
            msg += f", tensions [{', '.join(f'{t:.4g}' for t in w['tensions'])}] N"
    return msg


def register(app: typer.Typer) -> None:
    app.command("size-motors")(size_motors)
    app.command()(report)
    app.command()(check)
