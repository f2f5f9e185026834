"""The ``size-motors``, ``report`` and ``check`` jobs: motor sizing, the design report, requirement checks."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np

from cdpr_design.io.columns import file_name
from cdpr_design.io.files import OutputDir
from cdpr_design.jobs.common import Progress, output_dir, stage, submit_pictures
from cdpr_design.jobs.tables import Timings, write_table
from cdpr_design.jobs.motion import design_samples, trajectory_samples
from cdpr_design.jobs.workspace import WorkspaceSettings, finish_workspace, start_workspace
from cdpr_design.plots.report import report_html
from cdpr_design.plots.worker import PictureWorker
from cdpr_design.statics.robot import Analysis, resolve
from cdpr_design.workspaces.grid import check_step


def write_motor_sizing(out: OutputDir, sizing, format: str = "csv", design=None) -> Path:
    """``motor_sizing.csv`` (or ``.parquet``): one row per cable, the contract columns first (cli.md)."""
    from cdpr_design.design.sizing import AxisSizing

    rows = sizing.rows()
    header = list(rows[0].keys()) if rows else list(AxisSizing.CONTRACT)
    cols = {k: [r[k] for r in rows] for k in header}
    return write_table(out, "motor_sizing", cols, format, design, names=header, cycle=sizing.cycle,
                       safety_factor=sizing.safety_factor)


def write_design_report(out: OutputDir, row: dict, stem: str = "design_report", format: str = "csv",
                        design=None) -> Path:
    """``design_report.csv`` (or ``.parquet``): one row of the design's headline figures (booleans as 1/0)."""
    return write_table(out, stem, {k: [v] for k, v in row.items()}, format, design)


class SizingRun(NamedTuple):
    result: object  # design.sizing.SizingResult
    out: OutputDir
    summary: dict  # the ``size-motors --json`` object (result.summary() and its timings)


def size_motors(design, catalogue: Path | None = None, trajectory: str | None = None, safety_factor: float | None = None,
                motor: str | None = None, step: float | None = None, out: str | Path | None = None,
                overwrite: bool = False, engine: str = "auto", format: str = "csv",
                time_optimal: bool = False) -> SizingRun:
    """The ``size-motors`` command: size motor, gearbox and drum over the task workspace
    (grid ``step`` [m]; duty cycle of spec ``trajectory``, else a standard one) from the
    shipped catalogue extended by the YAML file ``catalogue``; write motor_sizing.csv
    (``format='parquet'``: ``.parquet``) into ``out``.  ``time_optimal``: the trajectory timed as
    fast as the robot allows (:mod:`cdpr_design.motion.time_optimal`)."""
    from cdpr_design.design import sizing as sz
    from cdpr_design.model import spec

    timings = Timings()
    cat = spec.load_catalogue(catalogue)
    robot = resolve(design, Analysis(command="size-motors", time_optimal=time_optimal))  # once: the trajectory's
    # samples and the sizing take it
    samples = trajectory_samples(robot, trajectory, time_optimal)
    out_dir = output_dir(design, out, overwrite)
    out_dir.target(file_name("motor_sizing", format))  # a foreign file: refused before any work
    with timings.phase("sweep_s"):
        result = sz.size_motors(robot, cat, step=step, samples=samples, safety_factor=safety_factor,
                                motor=motor, engine=engine)
        loads = frame_loads(design, step, engine)
    with timings.phase("write_s"), out_dir:
        write_motor_sizing(out_dir, result, format, design)
    return SizingRun(result, out_dir, {**result.summary(), **loads, "timings": timings.as_dict()})


def frame_loads(design, step: float | None = None, engine: str = "auto") -> dict:
    """The loads on the frame over the static workspace grid (``step`` [m]): the summary's
    ``frame_loads`` object and ``frame_loads_per_cable`` (``frame_loads.csv``'s rows as objects)."""
    from cdpr_design import workspaces as ws

    r = ws.run(design, ws.Analysis(engine=engine), step=step, keep_maps=False, tilt=False, frame_loads=True)
    cols = r.frame_loads.rows(design.cable_names)
    rows = [{k: (v[i] if k == "cable" or np.isfinite(v[i]) else None) for k, v in cols.items()}
            for i in range(design.m)]
    return {"frame_loads": r.summary()["frame_loads"], "frame_loads_per_cable": rows}


def evaluate(design, catalogue, trajectory=None, safety_factor: float | None = None,
             motor: str | None = None, step: float | None = None, workspace_result=None,
             progress: Progress | None = None, engine: str = "auto"):
    """Workspace, task box, motor sizing and checks of one design
    (:func:`cdpr_design.design.evaluate.evaluate_full`; ``catalogue``: a loaded motor catalogue,
    ``trajectory``: a spec trajectory's name or its samples, ``step`` [m])."""
    from cdpr_design.design import evaluate as ev

    samples = trajectory if trajectory is None or not isinstance(trajectory, str) else \
        design_samples(design, trajectory)
    with stage(progress, f"evaluate {design.name}") as cb:
        return ev.evaluate_full(design, step=step, catalogue=catalogue, samples=samples,
                                safety_factor=safety_factor, motor=motor,
                                workspace_result=workspace_result, progress=cb, engine=engine)


class CheckRun(NamedTuple):
    evaluation: object  # design.evaluate.Evaluation
    checks: list


def check(design, catalogue: Path | None = None, trajectory: str | None = None, safety_factor: float | None = None,
          motor: str | None = None, step: float | None = None, progress: Progress | None = None,
          engine: str = "auto") -> CheckRun:
    """The ``check`` command: evaluate the design and tabulate its requirements (nothing written);
    ``catalogue``: YAML file extending the shipped motor catalogue."""
    from cdpr_design.design import evaluate as ev
    from cdpr_design.model import spec

    e = evaluate(design, spec.load_catalogue(catalogue), trajectory, safety_factor, motor, step, progress=progress,
                 engine=engine)
    return CheckRun(e, ev.check_table(e.row))


class ReportRun(NamedTuple):
    evaluation: object  # design.evaluate.Evaluation
    checks: list
    out: OutputDir
    timings: dict  # the job's timings (also in report.json)


def report(design, catalogue: Path | None = None, trajectory: str | None = None, safety_factor: float | None = None,
           motor: str | None = None, step: float | None = None, force: bool = False,
           out: str | Path | None = None, overwrite: bool = False, pictures: PictureWorker | None = None,
           engine: str = "auto", progress: Progress | None = None, format: str = "csv") -> ReportRun:
    """The ``report`` command: the static workspace (:func:`~cdpr_design.jobs.workspace.start_workspace`;
    its pictures are drawn during the evaluation),
    then motor_sizing.csv, design_report.csv (``format='parquet'``: ``.parquet``), report.json and
    report.html of the evaluation; ``catalogue``: YAML file extending the shipped motor catalogue."""
    from cdpr_design.design import evaluate as ev
    from cdpr_design.model import spec

    from cdpr_design.design import sizing as sz

    timings = Timings()
    # every option checked before the first file is written (the workspace's)
    cat = spec.load_catalogue(catalogue)
    samples = design_samples(design, trajectory)  # an unknown name: --trajectory, before any work
    sz.check_options(design, cat, safety_factor, motor)
    if step is not None:
        check_step(step, "--step")
    out_dir = output_dir(design, out, overwrite)
    for name in (file_name("motor_sizing", format), file_name("design_report", format), "report.html", "report.json"):
        out_dir.target(name)
    with out_dir:  # every file put in place together at the end
        settings = WorkspaceSettings(Analysis(engine=engine), step=step, force=force, format=format)
        wres, drawing = start_workspace(design, out_dir, settings, pictures, progress, timings)
        with timings.phase("sweep_s"):  # while the workspace pictures are drawn
            e = evaluate(design, cat, samples, safety_factor, motor, step, wres, progress, engine)
            checks = ev.check_table(e.row)
        finish_workspace(out_dir, wres, drawing, timings)
        page = submit_pictures(out_dir, [("report.html", report_html, (wres, e.sizing, checks))], pictures, timings)
        with timings.phase("write_s"):
            write_motor_sizing(out_dir, e.sizing, format, design)
            write_design_report(out_dir, e.row, format=format, design=design)
        page.wait()
        t = timings.as_dict()
        out_dir.write_json("report.json", {"report": e.row, "checks": checks, "sizing": e.sizing.summary(),
                                           "timings": t})
    return ReportRun(e, checks, out_dir, t)
